"""One definition per call, for the async client and its blocking facade.

:class:`~pymotoros.client.calls.RobotCalls` defines every call of the client once, as a
method with its real signature and documentation. :class:`~pymotoros.client.RobotClient`
and :class:`~pymotoros.client.SyncRobotClient` both inherit them; the decorators here
make one definition behave as each class needs:

* :class:`blocking_twin` on a coroutine method: awaited on the async client; on a
  :class:`BlockingFacade` it runs on the facade's event loop and returns the result.
* :class:`facade_plain` on a plain method: called on the async client, on the facade
  too (the facade passes its client).

Both keep the method's parameters through :class:`typing.ParamSpec`, so mypy checks
``await robot.move_joints(...)`` and the facade's blocking ``robot.move_joints(...)``
against the one signature, and go-to-definition on either lands on that method. A new
wire request is one method in ``calls.py``, for both clients.
"""

from __future__ import annotations

import functools
import types
from abc import ABC, abstractmethod
from collections.abc import Callable, Coroutine
from typing import Any, Concatenate, Generic, ParamSpec, TypeVar, overload

_P = ParamSpec("_P")
_R = TypeVar("_R")
_S = TypeVar("_S")
_T = TypeVar("_T")


class BlockingFacade(ABC):
    """A blocking facade over an async client: runs the client's coroutines on an event
    loop of its own and waits for them (:class:`~pymotoros.client.SyncRobotClient`)."""

    client: Any
    """The async client behind the facade (the ``self`` its calls run with)."""

    @abstractmethod
    def run(self, coro: Coroutine[Any, Any, _T]) -> _T:
        """Run ``coro`` on the facade's event loop and block until it returns its result."""

    @abstractmethod
    def wait_for_first_state(self) -> None:
        """Block until the first state message is in (a no-op once it is)."""


class blocking_twin(Generic[_S, _P, _R]):  # noqa: N801 - used as a decorator, named as one
    """A coroutine method of the client, and its blocking twin on a :class:`BlockingFacade`.

    On the async client it is the method as written (on the class: the function); on a
    facade it is a plain function with the same parameters that runs the coroutine on the
    facade's loop (:meth:`BlockingFacade.run`: an interrupt stops a moving robot first),
    and on the facade's class the same, taking the facade first."""

    def __init__(self, method: Callable[Concatenate[_S, _P], Coroutine[Any, Any, _R]]) -> None:
        self.method = method
        self.__doc__ = method.__doc__
        self.__name__ = method.__name__
        self.__wrapped__ = method  # inspect.signature() and help() show the method's

    @functools.cached_property
    def _on_facade(self) -> Callable[..., Any]:
        """The blocking function, taking the facade first (bound to it on an instance)."""
        method = self.method

        @functools.wraps(method)  # the signature and the documentation are the method's
        def blocking(facade: BlockingFacade, /, *args: Any, **kwargs: Any) -> Any:
            return facade.run(method(facade.client, *args, **kwargs))

        return blocking

    @overload
    def __get__(
        self, obj: None, owner: type[BlockingFacade]
    ) -> Callable[Concatenate[BlockingFacade, _P], _R]: ...
    @overload
    def __get__(
        self, obj: None, owner: type[Any]
    ) -> Callable[Concatenate[_S, _P], Coroutine[Any, Any, _R]]: ...
    @overload
    def __get__(self, obj: BlockingFacade, owner: type[Any]) -> Callable[_P, _R]: ...
    @overload
    def __get__(self, obj: _S, owner: type[Any]) -> Callable[_P, Coroutine[Any, Any, _R]]: ...
    def __get__(self, obj: object, owner: type[Any]) -> Any:
        on_facade = issubclass(owner, BlockingFacade)
        function = self._on_facade if on_facade else self.method
        return function if obj is None else types.MethodType(function, obj)


class facade_plain(Generic[_S, _P, _R]):  # noqa: N801 - used as a decorator, named as one
    """A plain (non-async) method of the client; on a :class:`BlockingFacade` it is called
    on the facade's client. ``after_first_state``: the facade first waits for the first
    state message (a script calls, e.g., ``tcp_pose()`` right after connecting)."""

    def __init__(
        self, method: Callable[Concatenate[_S, _P], _R], *, after_first_state: bool = False
    ) -> None:
        self.method = method
        self.after_first_state = after_first_state
        self.__doc__ = method.__doc__
        self.__name__ = method.__name__
        self.__wrapped__ = method  # inspect.signature() and help() show the method's

    @functools.cached_property
    def _on_facade(self) -> Callable[..., Any]:
        """The method called on the facade's client, taking the facade first."""
        method, wait = self.method, self.after_first_state

        @functools.wraps(method)  # the signature and the documentation are the method's
        def plain(facade: BlockingFacade, /, *args: Any, **kwargs: Any) -> Any:
            if wait:
                facade.wait_for_first_state()
            return method(facade.client, *args, **kwargs)

        return plain

    @overload
    def __get__(
        self, obj: None, owner: type[BlockingFacade]
    ) -> Callable[Concatenate[BlockingFacade, _P], _R]: ...
    @overload
    def __get__(self, obj: None, owner: type[Any]) -> Callable[Concatenate[_S, _P], _R]: ...
    @overload
    def __get__(self, obj: _S | BlockingFacade, owner: type[Any]) -> Callable[_P, _R]: ...
    def __get__(self, obj: object, owner: type[Any]) -> Any:
        on_facade = issubclass(owner, BlockingFacade)
        function = self._on_facade if on_facade else self.method
        return function if obj is None else types.MethodType(function, obj)


def after_first_state(method: Callable[Concatenate[_S, _P], _R]) -> facade_plain[_S, _P, _R]:
    """:class:`facade_plain` for a method that reads the latest state: on the facade it
    first waits for the first state message."""
    return facade_plain(method, after_first_state=True)
