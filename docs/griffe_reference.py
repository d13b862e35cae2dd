"""A griffe extension for the API reference: the docstrings' reST roles as Markdown links,
and the blocking facade's calls shown as the blocking methods they are.

The client's calls are defined once, in ``pymotoros.client.calls.RobotCalls``, and both
``RobotClient`` and ``SyncRobotClient`` inherit them (the pages show inherited members).
A call decorated with ``@blocking_twin`` is a coroutine method on ``RobotClient`` and a
blocking one on ``SyncRobotClient`` (``pymotoros.client.blocking``); a static reader
sees ``async def`` for both. For a class deriving from ``BlockingFacade``, this extension
puts a copy of each such inherited call on the class: the same parameters, return
annotation and docstring, without ``async``, with a note that it blocks. It changes only
what the reference shows, never the package.

mkdocs.yml loads it for mkdocstrings; tests/test_api_reference.py loads it for the check
that every public name has a docstring, so both see the same API.
"""

from __future__ import annotations

import html
import re
from collections.abc import Callable, Iterator
from typing import Any

import griffe

BLOCKING_DECORATOR = "blocking_twin"
"""pymotoros.client.blocking's decorator of a call that blocks on the facade."""

CALL_DECORATORS = frozenset({BLOCKING_DECORATOR, "facade_plain", "after_first_state"})
"""pymotoros.client.blocking's decorators: a method with one is a call of both clients."""

BLOCKING_BASE = "BlockingFacade"
"""pymotoros.client.blocking's base class of the blocking facade."""


_ROLE = re.compile(r":(?:class|meth|func|mod|attr|exc|data|obj|const):`(~?)([^`]+)`")
"""A Sphinx cross-reference role (``:class:`~pymotoros.client.RobotClient```)."""


class ReferenceView(griffe.Extension):
    """Show the blocking facade's calls as blocking methods, and write the docstrings'
    reST roles as Markdown."""

    def on_package(self, *, pkg: griffe.Module, loader: griffe.GriffeLoader, **kwargs: Any) -> None:
        if pkg.name != "pymotoros":
            return
        for cls in [obj for obj in _objects(pkg) if isinstance(obj, griffe.Class)]:
            if any(str(base).rpartition(".")[2] == BLOCKING_BASE for base in cls.bases):
                _blocking_copies(cls)
        for obj in _objects(pkg):
            if obj.docstring is not None:
                obj.docstring.value = markdown(obj.docstring.value, _resolver(obj))


def markdown(text: str, resolve: Callable[[str], str | None] = lambda target: None) -> str:
    """The docstrings are written for Sphinx-like readers (roles, ``::`` before a literal
    block); the reference renders Markdown. A role becomes the name as the source writes it
    (the last part where ``~`` asks for it) in code, linked to the object's page where
    ``resolve`` finds its full path and the reference shows it (an *optional* autorefs
    link: one the reference does not show stays plain code, without a warning). ``::``
    ending a paragraph becomes a colon and a ``::`` line of its own goes (the indented
    block under either is a code block in Markdown too)."""

    def reference(match: re.Match[str]) -> str:
        tilde, target = match.group(1), match.group(2)
        code = f"<code>{html.escape(target.rsplit('.', 1)[-1] if tilde else target)}</code>"
        identifier = resolve(target)
        if identifier is None:
            return code
        return f'<autoref identifier="{html.escape(identifier)}" optional>{code}</autoref>'

    text = _ROLE.sub(reference, text)
    text = re.sub(r"^[ \t]*::[ \t]*$", "", text, flags=re.MULTILINE)  # a lone marker
    return re.sub(r"(?<=\S)::$", ":", text, flags=re.MULTILINE)


def _resolver(obj: griffe.Object) -> Callable[[str], str | None]:
    """A role's target as a full path: as written when it is one, else its first part
    looked up in the scope of the object the docstring belongs to (its members, its
    module's imports, then its parents')."""

    def resolve(target: str) -> str | None:
        if target.startswith("pymotoros."):
            return target
        head, _, rest = target.partition(".")
        try:
            path = obj.resolve(head)
        except (
            griffe.NameResolutionError,
            griffe.AliasResolutionError,
            griffe.CyclicAliasError,
            KeyError,
            ValueError,
        ):
            return None
        return f"{path}.{rest}" if rest else path

    return resolve


def _objects(obj: griffe.Object) -> Iterator[griffe.Object]:
    """Every object defined in ``obj`` (not the names it imports), ``obj`` included."""
    yield obj
    for member in list(obj.members.values()):
        if not member.is_alias and isinstance(member, griffe.Object):
            yield from _objects(member)


def _blocking_copies(cls: griffe.Class) -> None:
    """Put on ``cls`` a copy of every call it inherits (a method decorated by
    ``pymotoros.client.blocking``), a ``@blocking_twin`` one as a blocking method. As the
    class's own members they show on its page under its name, and a cross-reference to
    the call's definition still has one inherited entry (``RobotClient``'s) to go to."""
    for name, member in list(cls.inherited_members.items()):
        target = member.final_target if member.is_alias else member
        if not isinstance(target, griffe.Function) or name in cls.members:
            continue
        decorators = {str(d.value).rpartition(".")[2] for d in target.decorators}
        if not decorators & CALL_DECORATORS:
            continue
        blocking = BLOCKING_DECORATOR in decorators
        text = target.docstring.value if target.docstring else ""
        if blocking:
            text += (
                "\n\nBlocking: runs the call on the facade's event loop and waits for its"
                f" result (`RobotClient.{name}` awaits it)."
            )
        function = griffe.Function(
            name,
            parameters=target.parameters,
            returns=target.returns,
            lineno=target.lineno,
            endlineno=target.endlineno,
            docstring=griffe.Docstring(text.strip(), parent=None) if text else None,
        )
        function.labels |= set(target.labels) - {"async"} if blocking else set(target.labels)
        cls.set_member(name, function)
        target.aliases.pop(f"{cls.path}.{name}", None)  # the copy is no alias of the call
        if function.docstring is not None:
            function.docstring.parent = function
