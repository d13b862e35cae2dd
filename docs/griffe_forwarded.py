"""A griffe extension for the API reference: forwarded methods shown as the methods they are,
and the docstrings' reST roles as Markdown links.

``RobotClient`` is a facade over its parts (``move_joints = _part("_motion",
Motion.move_joints)``) and ``SyncRobotClient`` a blocking facade over ``RobotClient``
(``move_joints = _forward(RobotClient.move_joints)``). At run time each of these is a
function with the forwarded method's name, parameters and docstring (``functools.wraps``);
a static reader (griffe, which mkdocstrings renders with) sees only a class attribute
holding a call. This extension turns such an attribute back into the function it is at run
time: the target's parameters, return annotation and docstring, so the reference shows
``RobotClient.move_joints(...)`` with its documentation instead of an undocumented
``move_joints = _part(...)``. It changes only what the reference shows, never the package.

Which attributes: a class attribute whose value is a call of a module-private helper
(a name starting with ``_``) whose last argument names a function (``Motion.move_joints``),
or a plain name of another such method (``enable = start_trajectory_mode``). Helpers in
``BLOCKING_HELPERS`` make a coroutine function a blocking one: the copy loses ``async``.

mkdocs.yml loads it for mkdocstrings; tests/test_api_reference.py loads it for the check
that every public name has a docstring, so both see the same API.
"""

from __future__ import annotations

import html
import re
from collections.abc import Callable, Iterator
from typing import Any

import griffe

BLOCKING_HELPERS = frozenset({"_forward"})
"""pymotoros.client.sync's helper that runs a coroutine on the facade's loop and waits."""


_ROLE = re.compile(r":(?:class|meth|func|mod|attr|exc|data|obj|const):`(~?)([^`]+)`")
"""A Sphinx cross-reference role (``:class:`~pymotoros.client.RobotClient```)."""


class ForwardedMethods(griffe.Extension):
    """Replace forwarding attributes of pymotoros classes by copies of their targets, and
    write the docstrings' reST roles as Markdown."""

    def on_package(self, *, pkg: griffe.Module, loader: griffe.GriffeLoader, **kwargs: Any) -> None:
        if pkg.name != "pymotoros":
            return
        for cls in [obj for obj in _objects(pkg) if isinstance(obj, griffe.Class)]:
            for name in list(cls.members):
                _replace(cls, name, loader)
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


def _replace(cls: griffe.Class, name: str, loader: griffe.GriffeLoader) -> griffe.Function | None:
    """The function ``cls.name`` forwards to, put in its place (None: not a forwarder)."""
    member = cls.members[name]
    if isinstance(member, griffe.Function):
        return member
    if not isinstance(member, griffe.Attribute) or member.value is None:
        return None
    value = member.value
    blocking = False
    if isinstance(value, griffe.ExprCall):
        helper = str(value.function)
        if not helper.startswith("_") or not value.arguments:
            return None
        blocking = helper in BLOCKING_HELPERS
        value = value.arguments[-1]
    if isinstance(value, griffe.ExprName) and value.name in cls.members and value.name != name:
        target: griffe.Function | None = _replace(cls, value.name, loader)  # enable = start_...
    elif isinstance(value, griffe.ExprAttribute | griffe.ExprName):
        target = _function_at(value.canonical_path, loader)
    else:
        return None
    if target is None:
        return None
    labels = set(target.labels) - {"async"} if blocking else set(target.labels)
    text = target.docstring.value if target.docstring else ""
    if member.docstring:  # the attribute's own note, e.g. SyncRobotClient.stop's
        text = f"{text}\n\n{member.docstring.value}".strip()
    if blocking:
        text += (
            f"\n\nBlocking: runs `RobotClient.{target.name}` on the facade's event loop and"
            " waits for its result."
        )
    function = griffe.Function(
        name,
        parameters=target.parameters,
        returns=target.returns,
        lineno=member.lineno,
        endlineno=member.endlineno,
        docstring=griffe.Docstring(text, parent=None) if text else None,
    )
    function.labels |= labels
    cls.set_member(name, function)
    if function.docstring is not None:
        function.docstring.parent = function
    return function


def _function_at(path: str, loader: griffe.GriffeLoader) -> griffe.Function | None:
    """The function at a dotted path, following the same rule through the class that holds
    it (``RobotClient.move_joints`` is itself a forwarder to ``Motion.move_joints``)."""
    owner_path, _, name = path.rpartition(".")
    if not owner_path.startswith("pymotoros."):
        return None
    try:
        owner = loader.modules_collection[owner_path]
    except (KeyError, griffe.AliasResolutionError, griffe.CyclicAliasError):
        return None
    if owner.is_alias:
        owner = owner.final_target
    if not isinstance(owner, griffe.Class) or name not in owner.members:
        return None
    return _replace(owner, name, loader)
