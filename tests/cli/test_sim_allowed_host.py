"""``pymotoros sim --allowed-host``: the names a user adds reach the served control API,
and a DNS-rebinding Host is refused by the running process (issue 28, item 2)."""

from __future__ import annotations

import json
import sys
import urllib.error
import urllib.request
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "client"))
from client_sim import Sim, running_sim


def get_state(sim: Sim, host: str) -> tuple[int, str]:
    request = urllib.request.Request(
        f"http://127.0.0.1:{sim.http}/api/state", headers={"Host": host}
    )
    try:
        with urllib.request.urlopen(request, timeout=10) as reply:  # noqa: S310
            return reply.status, ""
    except urllib.error.HTTPError as exc:
        with exc:
            return exc.code, json.loads(exc.read())["error"]


def test_sim_serves_the_names_it_is_given_and_refuses_others() -> None:
    with running_sim("--allowed-host", "twin.lab", "--allowed-host", ".robots.example") as sim:
        assert get_state(sim, f"twin.lab:{sim.http}") == (200, "")
        assert get_state(sim, "cell-3.robots.example")[0] == 200
        assert get_state(sim, f"localhost:{sim.http}")[0] == 200
        status, error = get_state(sim, f"rebind.attacker.example:{sim.http}")
        assert status == 403
        assert "--allowed-host rebind.attacker.example" in error


def test_every_cell_of_a_fleet_gets_the_allowed_names() -> None:
    """``--config a.toml --config b.toml``: one list of names for every cell's API."""
    from pymotoros.cli.sim_cells import _fleet_cell
    from pymotoros.controller.cell import cell_from_file
    from pymotoros.models.cell import read_cell_file

    examples = Path(__file__).resolve().parents[2] / "examples" / "cells"
    for name in ("hc10_yrc1000.toml", "two_hc10_dx100.toml"):
        cell_file = read_cell_file(examples / name)
        cell = _fleet_cell(
            name, cell_from_file(cell_file), cell_file.ports, "127.0.0.1", None, ("twin.lab",)
        )
        assert cell.config.allowed_hosts == ("twin.lab",)
