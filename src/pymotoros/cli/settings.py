"""Where CLI options come from besides the command line: environment and a settings file.

Precedence, highest first (documented in ``docs/client.md``)::

    command-line flag  >  environment variable  >  settings file  >  built-in default

* Environment: the options every robot command shares have short names
  (``PYMOTOROS_HOST``, ``PYMOTOROS_MOTION_PORT``, ``PYMOTOROS_PORTS_FILE``,
  ``PYMOTOROS_CONFIG`` …); every other option is ``PYMOTOROS_<COMMAND>_<OPTION>``
  after its long flag (``PYMOTOROS_MOVE_SPEED_SCALE``, ``PYMOTOROS_STATUS_JSON``,
  ``PYMOTOROS_IO_READ_GROUP``, ``PYMOTOROS_SIM_HTTP_PORT``).
* Settings file: TOML, from ``PYMOTOROS_SETTINGS`` or else the first of
  ``./pymotoros.toml`` and ``~/.config/pymotoros/config.toml``. Top-level keys apply to
  every command that has the option; a ``[move]`` (``[io.read]`` …) table to one
  command. Option names as on the command line, without the dashes.

Click already orders command line > environment > ``default_map`` > default; this module
builds the ``default_map`` from the file and refuses keys no command knows.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any, Final, TypeVar

import click

from pymotoros.errors import ConfigError
from pymotoros.models.toml_file import read_toml

_F = TypeVar("_F", bound=Callable[..., Any])

ENV_PREFIX: Final = "PYMOTOROS"
SETTINGS_ENV: Final = "PYMOTOROS_SETTINGS"
LOCAL_SETTINGS: Final = Path("pymotoros.toml")
USER_SETTINGS: Final = Path("~/.config/pymotoros/config.toml")

_ALIASES: Final = {
    "timeout": "timeout_s",
    "json": "as_json",
    "controller": "controller_name",
    "robot": "robot_name",
    "config": "config_path",
}
"""Option name -> the Python parameter name some commands give it (both are set)."""

SHARED_KEYS: Final = frozenset(
    {
        "host",
        "motion_port",
        "state_port",
        "io_port",
        "http_port",
        "controller",
        "robot",
        "timeout",
        "config",
        "ports_file",
        "cell",
        "debug",
        "deg",
        "token",
    }
)
"""Keys allowed at the top of the settings file (options several commands share)."""


def envvar(name: str) -> str:
    """A shared option's environment variable: ``envvar("io_port")`` is PYMOTOROS_IO_PORT."""
    return f"{ENV_PREFIX}_{name.upper()}"


def cell_option(func: _F) -> _F:
    """``--cell NAME`` (``PYMOTOROS_CELL``): which cell of a ports file a robot command
    talks to, when ``pymotoros sim`` runs several (``--config a.toml --config b.toml``)."""
    option = click.option(
        "--cell",
        default=None,
        envvar=envvar("cell"),
        metavar="NAME",
        help="The cell of the --ports-file to talk to, by the name on its ready line "
        "(cell=NAME); needed when the simulator runs several cells.",
    )
    return option(func)


def name_envvars(command: click.Command, prefix: str) -> None:
    """Give every option without one the variable ``PREFIX_<LONG FLAG>`` (``--json`` of
    ``status`` → PYMOTOROS_STATUS_JSON), named after the flag users type rather than
    after the Python parameter (``as_json``) as click's automatic names would be."""
    for param in command.params:
        if isinstance(param, click.Option) and param.envvar is None:
            longest = max(param.opts, key=len).lstrip("-").replace("-", "_").upper()
            param.envvar = f"{prefix}_{longest}"
    if isinstance(command, click.Group):
        for name, sub in command.commands.items():
            name_envvars(sub, f"{prefix}_{name.upper()}")


def settings_path() -> Path | None:
    """The settings file in use, or None when there is none."""
    named = os.environ.get(SETTINGS_ENV)
    if named:
        path = Path(named).expanduser()
        if not path.is_file():
            raise ConfigError(
                f"{SETTINGS_ENV}={named}: no such file (unset it or point it at a TOML file)"
            )
        return path
    for candidate in (LOCAL_SETTINGS, USER_SETTINGS.expanduser()):
        if candidate.is_file():
            return candidate
    return None


def _normalise(key: str) -> str:
    return key.replace("-", "_")


def _with_aliases(values: Mapping[str, object]) -> dict[str, object]:
    out: dict[str, object] = {}
    for key, value in values.items():
        name = _normalise(key)
        out[name] = value
        if name in _ALIASES:
            out[_ALIASES[name]] = value
    return out


def load_settings(path: Path, commands: Iterable[str]) -> dict[str, Any]:
    """The ``default_map`` for the ``pymotoros`` group from the settings file ``path``."""
    data = read_toml(path, "settings file")
    names = set(commands)
    shared: dict[str, object] = {}
    sections: dict[str, Mapping[str, object]] = {}
    for key, value in data.items():
        if isinstance(value, Mapping):
            if key not in names:
                raise ConfigError(
                    f"{path}: [{key}]: no such command (commands: {', '.join(sorted(names))})"
                )
            sections[key] = value
        elif _normalise(key) in SHARED_KEYS:
            shared[key] = value
        else:
            raise ConfigError(
                f"{path}: {key}: not an option every command shares "
                f"({', '.join(sorted(SHARED_KEYS))}); put it in a [command] table"
            )
    result: dict[str, Any] = {}
    for name in names:
        section = dict(sections.get(name, {}))
        subs = {k: v for k, v in section.items() if isinstance(v, Mapping)}
        plain = {k: v for k, v in section.items() if not isinstance(v, Mapping)}
        entry: dict[str, Any] = _with_aliases({**shared, **plain})
        for sub, values in subs.items():
            entry[sub] = _with_aliases({**shared, **plain, **values})
        for sub in ("read", "write"):  # the subcommands of io and mreg get the shared keys
            entry.setdefault(sub, _with_aliases({**shared, **plain}))
        result[name] = entry
    return result


def name_the_source(exc: click.BadParameter, args: Sequence[str]) -> click.BadParameter:
    """A bad option value that did not come from the command line (``args``, what the
    user typed after the command's name), named by where it came from: the environment
    variable (``PYMOTOROS_MOTION_PORT``) or the settings file's key, not the flag
    (``--motion-port``) the user never typed."""
    param = exc.param
    if not isinstance(param, click.Option) or exc.param_hint is not None:
        return exc
    flags = [*param.opts, *param.secondary_opts]
    if any(arg == flag or arg.startswith(f"{flag}=") for arg in args for flag in flags):
        return exc  # typed on the command line: click's words are right
    flag = max(param.opts, key=len)
    variables = [param.envvar] if isinstance(param.envvar, str) else list(param.envvar or ())
    hint = next(
        (f"{v} (the environment variable of {flag})" for v in variables if v in os.environ), None
    )
    name = param.name or ""
    if hint is None and exc.ctx is not None and exc.ctx.lookup_default(name) is not None:
        key = next((k for k, v in _ALIASES.items() if v == name), name)
        hint = f"{key} in the settings file {settings_path()} ({flag})"
    if hint is None:
        return exc
    return click.BadParameter(exc.message, ctx=exc.ctx, param=param, param_hint=hint)


def check_section(ctx: click.Context, command: click.Command) -> None:
    """Refuse a settings-file key the command has no option for (nothing silently ignored)."""
    table = (ctx.default_map or {}).get(command.name or "")
    if not isinstance(table, Mapping) or isinstance(command, click.Group):
        return
    known = {p.name for p in command.params if p.name}
    for key in table:
        if isinstance(table[key], Mapping) or key in known or _normalise(key) in SHARED_KEYS:
            continue
        if _ALIASES.get(key) in known or key in _ALIASES.values():
            continue
        raise click.UsageError(
            f"settings file: [{command.name}] {key}: the command has no such option "
            f"(options: {', '.join(sorted(k for k in known if k))})"
        )


__all__ = [
    "ENV_PREFIX",
    "SETTINGS_ENV",
    "cell_option",
    "check_section",
    "envvar",
    "load_settings",
    "name_envvars",
    "name_the_source",
    "settings_path",
]
