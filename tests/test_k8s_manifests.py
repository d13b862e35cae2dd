"""The Kubernetes recipe (deploy/k8s, issue 23), checked offline without a cluster.

- ``kubernetes-validate`` (the test extra; it ships the Kubernetes JSON schemas, so no
  network is needed) accepts every manifest in strict mode (unknown fields refused);
- the manifests agree with the image and the twin: the container ports are the
  Dockerfile's EXPOSE, the probes ask endpoints the control API serves without a token,
  the token comes from the Secret as PYMOTOROS_TOKEN, the args are options ``pymotoros
  sim`` accepts, the cell in the ConfigMap loads, and the resources are set.
"""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path
from typing import Any

import click
import pytest
import yaml

from pymotoros.cli.sim import sim
from pymotoros.controller.cell import load_cell
from pymotoros.runtime.access import guarded

ROOT = Path(__file__).resolve().parents[1]
K8S = ROOT / "deploy" / "k8s"
VALIDATE_TIMEOUT_S = 120


def manifests() -> dict[str, dict[str, Any]]:
    out: dict[str, dict[str, Any]] = {}
    for path in sorted(K8S.glob("*.yaml")):
        for doc in yaml.safe_load_all(path.read_text()):
            out[doc["kind"]] = doc
    return out


def container() -> dict[str, Any]:
    spec = manifests()["StatefulSet"]["spec"]["template"]["spec"]
    (twin,) = spec["containers"]
    assert isinstance(twin, dict)
    return twin


def test_every_manifest_validates_against_the_kubernetes_schemas() -> None:
    files = sorted(str(p) for p in K8S.glob("*.yaml"))
    assert len(files) >= 4
    tool = shutil.which("kubernetes-validate")
    if tool is None:
        pytest.fail("kubernetes-validate is missing: pip install -e '.[test]'")
    done = subprocess.run(  # noqa: S603 - the validator on our own files
        [tool, "--strict", "--quiet", *files],
        capture_output=True,
        text=True,
        check=False,
        timeout=VALIDATE_TIMEOUT_S,
    )
    assert done.returncode == 0, done.stdout + done.stderr


def test_a_broken_manifest_is_caught(tmp_path: Path) -> None:
    """The validator really checks (a typo in a field fails in strict mode)."""
    bad = tmp_path / "bad.yaml"
    bad.write_text((K8S / "service.yaml").read_text().replace("targetPort:", "targetPrt:"))
    tool = shutil.which("kubernetes-validate")
    assert tool is not None, "kubernetes-validate is missing: pip install -e '.[test]'"
    done = subprocess.run(  # noqa: S603
        [tool, "--strict", "--quiet", str(bad)],
        capture_output=True,
        text=True,
        check=False,
        timeout=VALIDATE_TIMEOUT_S,
    )
    assert done.returncode != 0


def test_ports_probes_token_and_resources_match_the_twin() -> None:
    docs = manifests()
    twin = container()
    exposed = {
        int(p)
        for line in (ROOT / "Dockerfile").read_text().splitlines()
        if line.startswith("EXPOSE")
        for p in line.split()[1:]
    }
    ports = {p["name"]: p["containerPort"] for p in twin["ports"]}
    assert set(ports.values()) == exposed
    service = {p["name"]: p["port"] for p in docs["Service"]["spec"]["ports"]}
    assert service == ports
    assert docs["Service"]["spec"]["clusterIP"] == "None"  # one DNS name per twin
    for probe in ("readinessProbe", "livenessProbe"):
        path = twin[probe]["httpGet"]["path"]
        assert path in ("/healthz", "/readyz")
        assert not guarded(path)  # a probe cannot send the Secret's token
    (env,) = [e for e in twin["env"] if e["name"] == "PYMOTOROS_TOKEN"]
    ref = env["valueFrom"]["secretKeyRef"]
    assert ref["name"] == docs["Secret"]["metadata"]["name"]
    assert ref["key"] in docs["Secret"]["stringData"]
    requests = twin["resources"]["requests"]
    assert requests["cpu"] == "100m"  # ~8 % of a core streaming (docs/benchmarks.md)
    assert requests["memory"] == "96Mi"  # ~60 MiB PSS per twin, with headroom
    assert "cpu" not in twin["resources"].get("limits", {})  # throttling makes ticks late


def test_the_args_and_the_cell_are_what_the_sim_accepts(tmp_path: Path) -> None:
    cell = tmp_path / "cell.toml"
    cell.write_text(manifests()["ConfigMap"]["data"]["cell.toml"])
    loaded = load_cell(cell)
    assert loaded.name == "HC10 on YRC1000"
    args = [a.replace("/cells/cell.toml", str(cell)) for a in container()["args"]]
    try:
        sim.make_context("sim", ["--host", "0.0.0.0", *args])
    except click.UsageError as exc:
        pytest.fail(f"args {args}: pymotoros sim refuses them: {exc}")
