"""What ``pymotoros status --api URL`` adds from the simulator's control API.

A real controller shows PFL, FSU and alarm texts on its pendant only; the simulator's
``GET /api/state`` has them, so ``status`` can show them next to the wire's view. The
safety lines follow the safety unit's declared part of the snapshot
(:class:`~pymotoros.controller.safety.SafetySnapshot`): one line per safety function.
"""

from __future__ import annotations

import asyncio
import dataclasses
import json
import urllib.error
import urllib.request
from typing import Any, Final

from pymotoros.client.alarms import alarm_text
from pymotoros.errors import ConfigError

API_TIMEOUT_S: Final = 5.0


HOW_TO_AUTHENTICATE: Final = (
    "give the token the twin was started with (pymotoros sim --token): --token TOKEN, "
    "the PYMOTOROS_TOKEN environment variable or token in the settings file"
)
"""How to give the control API's token, in the words of a 401."""


def api_request(url: str, token: str | None) -> urllib.request.Request:
    """A GET of ``url`` with ``Authorization: Bearer TOKEN`` when a token is given."""
    headers = {"Accept": "application/json"}
    if token:
        headers["Authorization"] = f"Bearer {token.strip()}"
    return urllib.request.Request(url, headers=headers)  # noqa: S310 - http(s) checked by callers


def refusal_text(url: str, exc: urllib.error.HTTPError, token: str | None) -> str:
    """What an HTTP error from the control API means for the user: a 401 says the token
    is missing or wrong and how to give it; others carry the twin's own error text."""
    with exc:  # its socket: closed whatever the answer
        if exc.code == 401:
            what = "a token is needed and none was given" if not token else "the token was refused"
            return f"{url}: {what} (401); {HOW_TO_AUTHENTICATE}"
        try:
            body = json.loads(exc.read())
        except (OSError, ValueError):
            body = None
    detail = body.get("error") if isinstance(body, dict) else None
    return f"{url}: {exc.code} {exc.reason}" + (f": {detail}" if detail else "")


def fetch_state(api: str, token: str | None = None) -> dict[str, Any]:
    """``GET {api}/api/state`` (blocking), with the control API's ``token`` when given;
    ConfigError with the URL (and, for a 401, how to give the token) when it fails."""
    url = api.rstrip("/") + "/api/state"
    if not url.startswith(("http://", "https://")):
        raise ConfigError(
            f"--api must be an http:// URL such as http://127.0.0.1:8080, not {api!r}"
        )
    try:
        with urllib.request.urlopen(api_request(url, token), timeout=API_TIMEOUT_S) as reply:  # noqa: S310 - checked above
            doc = json.load(reply)
    except urllib.error.HTTPError as exc:
        raise ConfigError(
            f"cannot read the simulator's state: {refusal_text(url, exc, token)}"
        ) from exc
    except (OSError, ValueError) as exc:
        raise ConfigError(f"cannot read the simulator's state from {url}: {exc}") from exc
    if not isinstance(doc, dict):
        raise ConfigError(f"{url} did not answer a JSON object")
    return doc


async def fetch_state_async(api: str, token: str | None = None) -> dict[str, Any]:
    return await asyncio.to_thread(fetch_state, api, token)


def safety_keys() -> tuple[str, ...]:
    """The state document's keys that the safety unit contributes, one per safety
    function (the fields of :class:`~pymotoros.controller.safety.SafetySnapshot`): the
    ones this view has always shown first, in their order, then any other in field order,
    so a new safety function is shown with no edit here."""
    from pymotoros.controller.safety import SafetySnapshot  # numpy: only with --api

    names = [f.name for f in dataclasses.fields(SafetySnapshot)]
    known = [name for name in _LABELS if name in names]
    return tuple(known + [name for name in names if name not in _LABELS])


_LABELS: Final[dict[str, str]] = {"pfl": "PFL", "fsu": "FSU limit"}


def _fsu_text(fsu: Any) -> str:
    fsu = fsu or {}
    limits = []
    if fsu.get("joint_speed_pct") is not None:
        limits.append(f"joints {fsu['joint_speed_pct']} %")
    if fsu.get("tcp_speed_mm_s") is not None:
        limits.append(f"TCP {fsu['tcp_speed_mm_s']:g} mm/s")
    return ", ".join(limits) or "off"


def _text(value: Any) -> str:
    """A safety function's state in words: null and false are "off", true is "on", an
    object its keys and values."""
    if value is None or value is False:
        return "off"
    if value is True:
        return "on"
    if isinstance(value, dict):
        return ", ".join(f"{k} {_text(v)}" for k, v in value.items()) or "off"
    return str(value)


def safety_lines(doc: dict[str, Any] | None, error_code: int | None) -> list[str]:
    """The status table's extra lines: alarm texts, each safety function, MotoROS start-up."""
    lines: list[str] = []
    if doc is None:
        text = alarm_text(error_code) if error_code else ""
        if text:
            lines.append(f"  alarm text        {text}")
        return lines
    for alarm in doc.get("alarms", []):
        lines.append(
            f"  alarm             {alarm['code']}/{alarm['subcode']} {alarm['text']}".rstrip()
        )
    for key in safety_keys():
        value = doc.get(key)
        text = _fsu_text(value) if key == "fsu" else _text(value)
        label = _LABELS.get(key, key.replace("_", " "))
        lines.append(f"  {label:<18}{text}")
    motoros = doc.get("motoros", "running")
    if motoros != "running":
        lines.append(f"  MotoROS           {motoros}")
    return lines


def safety_data(doc: dict[str, Any] | None) -> dict[str, Any]:
    """The ``--json`` keys added from the control API (empty without ``--api``)."""
    if doc is None:
        return {}
    return {
        "alarms": doc.get("alarms", []),
        **{key: doc.get(key) for key in safety_keys()},
        "motoros": doc.get("motoros"),
    }
