"""The Kubernetes recipe (deploy/k8s, issues 23 and 28), checked offline without a cluster.

- ``kubernetes-validate`` (the test extra; it ships the Kubernetes JSON schemas, so no
  network is needed) accepts every manifest the kustomization applies, in strict mode
  (unknown fields refused), and the kustomization lists every manifest of the folder;
- the manifests agree with the image and the twin: the container ports are the
  Dockerfile's EXPOSE, the probes ask endpoints the control API serves without a token
  on the port named ``http``, which is the port the sim is told through
  PYMOTOROS_SIM_HTTP_PORT (the Service, the NetworkPolicy and the ServiceMonitor use the
  same name), the args are options ``pymotoros sim`` accepts, the cell in the ConfigMap
  loads, and the memory request covers the measured RSS of a twin (docs/fleet.md);
- no token is written anywhere in deploy/ (no Secret with data, no literal
  PYMOTOROS_TOKEN, no ``--token``): the Secret the StatefulSet and the ServiceMonitor
  name is the one docs/fleet.md's ``kubectl create secret`` command makes;
- Prometheus's scrape authenticates: the ServiceMonitor and the plain scrape config
  send the token as a bearer, and a twin configured like a pod answers a scrape made as
  they describe it (path, port, token read from the mounted file) with its metrics, and
  the same scrape without the token with 401.
"""

from __future__ import annotations

import re
import shlex
import shutil
import subprocess
import urllib.error
import urllib.request
from pathlib import Path
from typing import Any

import click
import pytest
import yaml

from container_sim import container_sim
from pymotoros.cli.sim import sim
from pymotoros.controller.cell import load_cell
from pymotoros.runtime.access import guarded

ROOT = Path(__file__).resolve().parents[1]
DEPLOY = ROOT / "deploy"
K8S = DEPLOY / "k8s"
MONITORING = K8S / "prometheus"
VALIDATE_TIMEOUT_S = 120
SCRAPE_TIMEOUT_S = 10

MEASURED_RSS_MIB = 150.1
"""Largest RSS of one twin, idle and streaming (docs/fleet.md, tools/measure_twin_memory.py)."""


def kustomization() -> dict[str, Any]:
    loaded = yaml.safe_load((K8S / "kustomization.yaml").read_text())
    assert isinstance(loaded, dict)
    return loaded


def manifest_files() -> list[Path]:
    return [K8S / name for name in kustomization()["resources"]]


def manifests() -> dict[str, dict[str, Any]]:
    out: dict[str, dict[str, Any]] = {}
    for path in manifest_files():
        for doc in yaml.safe_load_all(path.read_text()):
            out[doc["kind"]] = doc
    return out


def container() -> dict[str, Any]:
    spec = manifests()["StatefulSet"]["spec"]["template"]["spec"]
    (twin,) = spec["containers"]
    assert isinstance(twin, dict)
    return twin


def service_monitor() -> dict[str, Any]:
    loaded = yaml.safe_load((MONITORING / "servicemonitor.yaml").read_text())
    assert isinstance(loaded, dict)
    return loaded


def scrape_job() -> dict[str, Any]:
    config = yaml.safe_load((MONITORING / "scrape-config.yaml").read_text())
    (job,) = config["scrape_configs"]
    assert isinstance(job, dict)
    return job


def validate(files: list[str]) -> subprocess.CompletedProcess[str]:
    tool = shutil.which("kubernetes-validate")
    if tool is None:
        pytest.fail("kubernetes-validate is missing: pip install -e '.[test]'")
    return subprocess.run(  # noqa: S603 - the validator on our own files
        [tool, "--strict", "--quiet", *files],
        capture_output=True,
        text=True,
        check=False,
        timeout=VALIDATE_TIMEOUT_S,
    )


def test_every_manifest_validates_against_the_kubernetes_schemas() -> None:
    files = [str(p) for p in manifest_files()]
    assert len(files) >= 4
    done = validate(files)
    assert done.returncode == 0, done.stdout + done.stderr


def test_the_kustomization_applies_every_manifest_of_the_folder() -> None:
    listed = {p.name for p in manifest_files()}
    present = {p.name for p in K8S.glob("*.yaml")} - {"kustomization.yaml"}
    assert listed == present
    (image,) = kustomization()["images"]
    assert image["name"] == container()["image"].split(":")[0]  # what it rewrites


def test_a_broken_manifest_is_caught(tmp_path: Path) -> None:
    """The validator really checks (a typo in a field fails in strict mode)."""
    bad = tmp_path / "bad.yaml"
    bad.write_text((K8S / "service.yaml").read_text().replace("targetPort:", "targetPrt:"))
    assert validate([str(bad)]).returncode != 0


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
    for probe in ("readinessProbe", "livenessProbe", "startupProbe"):
        path = twin[probe]["httpGet"]["path"]
        assert path in ("/healthz", "/readyz")
        assert not guarded(path)  # a probe cannot send the Secret's token
    (env,) = [e for e in twin["env"] if e["name"] == "PYMOTOROS_TOKEN"]
    assert set(env) == {"name", "valueFrom"}
    assert env["valueFrom"]["secretKeyRef"] == documented_secret()
    requests = twin["resources"]["requests"]
    assert requests["cpu"] == "100m"  # ~8 % of a core streaming (docs/benchmarks.md)
    assert "cpu" not in twin["resources"].get("limits", {})  # throttling makes ticks late


def mebibytes(quantity: str) -> float:
    match = re.fullmatch(r"(\d+)(Mi|Gi)", quantity)
    assert match, f"{quantity}: give memory in Mi or Gi"
    return int(match[1]) * (1024 if match[2] == "Gi" else 1)


def test_the_memory_request_covers_the_measured_twin() -> None:
    """A pod's memory cgroup counts its RSS (nothing in the pod shares the libraries)."""
    resources = container()["resources"]
    request = mebibytes(resources["requests"]["memory"])
    limit = mebibytes(resources["limits"]["memory"])
    assert MEASURED_RSS_MIB <= request <= 1.25 * MEASURED_RSS_MIB, request
    assert limit >= 1.5 * MEASURED_RSS_MIB, limit
    fleet = (ROOT / "docs" / "fleet.md").read_text()
    assert f"{MEASURED_RSS_MIB:.1f}" in fleet, "record the measurement in docs/fleet.md"
    assert "tools/measure_twin_memory.py" in fleet
    assert f"{resources['requests']['memory']}" in fleet


def test_the_probes_and_everything_else_use_the_configured_http_port() -> None:
    twin = container()
    (env,) = [e for e in twin["env"] if e["name"] == "PYMOTOROS_SIM_HTTP_PORT"]
    ports = {p["name"]: p["containerPort"] for p in twin["ports"]}
    assert int(env["value"]) == ports["http"]  # the sim listens where the pod says
    assert "--http-port" not in twin.get("args", [])  # it would override the variable
    for probe in ("readinessProbe", "livenessProbe", "startupProbe"):
        assert twin[probe]["httpGet"]["port"] == "http", probe  # by name: follows it
    docs = manifests()
    (http,) = [p for p in docs["Service"]["spec"]["ports"] if p["name"] == "http"]
    assert http["targetPort"] == "http"
    policy_ports = [p["port"] for rule in docs["NetworkPolicy"]["spec"]["ingress"]
                    for p in rule["ports"]]  # fmt: skip
    assert ports["http"] not in policy_ports  # by name, not a number that could drift
    assert "http" in policy_ports
    for endpoint in service_monitor()["spec"]["endpoints"]:
        assert endpoint["port"] == "http"


def all_deploy_documents() -> list[tuple[Path, Any]]:
    return [(path, doc) for path in sorted(DEPLOY.rglob("*.yaml"))
            for doc in yaml.safe_load_all(path.read_text()) if doc]  # fmt: skip


def walk(node: Any) -> list[tuple[str, Any]]:
    """Every (key, value) pair in a YAML document, at any depth."""
    out: list[tuple[str, Any]] = []
    if isinstance(node, dict):
        for key, value in node.items():
            out.append((str(key), value))
            out.extend(walk(value))
    elif isinstance(node, list):
        for item in node:
            out.extend(walk(item))
    return out


def test_no_token_is_written_in_the_manifests() -> None:
    documents = all_deploy_documents()
    assert len(documents) >= 6
    for path, doc in documents:
        where = path.relative_to(ROOT)
        if isinstance(doc, dict) and doc.get("kind") == "Secret":
            assert not doc.get("data"), f"{where}: a literal token"
            assert not doc.get("stringData"), f"{where}: a literal token"
        for key, value in walk(doc):
            assert key not in ("bearer_token", "bearerToken", "password"), f"{where}: {key}"
            if key == "credentials":
                assert isinstance(value, dict), f"{where}: a literal credential"
        text = path.read_text()
        assert "change-me" not in text, where
        assert "--token" not in re.sub(r"#.*", "", text), f"{where}: a token on the command line"
    (env,) = [e for e in container()["env"] if e["name"] == "PYMOTOROS_TOKEN"]
    assert "value" not in env
    assert "change-me" not in (ROOT / "Dockerfile").read_text()


def documented_secret() -> dict[str, str]:
    """The Secret that docs/fleet.md's command creates, as a secretKeyRef."""
    fleet = (ROOT / "docs" / "fleet.md").read_text()
    commands = re.findall(r"^kubectl create secret generic .*$", fleet, re.MULTILINE)
    assert commands, "docs/fleet.md has no `kubectl create secret generic` command"
    argv = shlex.split(commands[0])
    literal = next(a for a in argv if a.startswith("--from-literal="))
    key, _, value = literal.removeprefix("--from-literal=").partition("=")
    assert value.startswith("$("), f"{value}: generate the token, do not write it"
    assert "secrets" in value, value
    return {"name": argv[4], "key": key}


def test_the_scrape_sends_the_token_from_the_secret() -> None:
    secret = documented_secret()
    (endpoint,) = service_monitor()["spec"]["endpoints"]
    assert service_monitor()["spec"]["selector"]["matchLabels"].items() <= (
        manifests()["Service"]["metadata"]["labels"].items()
    )
    assert endpoint["authorization"]["type"] == "Bearer"
    assert endpoint["authorization"]["credentials"] == secret
    assert guarded(endpoint["path"])  # without the token this scrape would get 401
    job = scrape_job()
    assert job["authorization"]["type"] == "Bearer"
    assert job["authorization"]["credentials_file"].endswith("/" + secret["key"])
    keep = {tuple(r["source_labels"]): r["regex"] for r in job["relabel_configs"]
            if r.get("action") == "keep"}  # fmt: skip
    assert keep[("__meta_kubernetes_pod_container_port_name",)] == "http"
    labels = container_labels()
    assert keep[("__meta_kubernetes_pod_label_app_kubernetes_io_name",)] == labels[
        "app.kubernetes.io/name"
    ]
    annotations = manifests()["StatefulSet"]["spec"]["template"]["metadata"].get(
        "annotations", {}
    )
    assert "prometheus.io/scrape" not in annotations  # such a scrape has no token: 401


def container_labels() -> dict[str, str]:
    labels = manifests()["StatefulSet"]["spec"]["template"]["metadata"]["labels"]
    assert isinstance(labels, dict)
    return labels


def scrape(url: str, token: str | None) -> tuple[int, str]:
    headers = {"Authorization": f"Bearer {token}"} if token is not None else {}
    request = urllib.request.Request(url, headers=headers)  # noqa: S310 - loopback http
    try:
        with urllib.request.urlopen(request, timeout=SCRAPE_TIMEOUT_S) as reply:  # noqa: S310
            return reply.status, reply.read().decode()
    except urllib.error.HTTPError as exc:
        return exc.code, exc.read().decode()


def test_a_scrape_made_as_configured_gets_the_metrics(tmp_path: Path) -> None:
    """The twin configured like a pod (token and port from the environment); the scrape
    as the scrape config describes it: its path, the token read from the file the
    Secret is mounted as (``kubectl create secret --from-literal`` adds no newline)."""
    job = scrape_job()
    with container_sim(tmp_path) as twin:
        credentials = tmp_path / "token"
        credentials.write_text(twin.token)
        url = f"{job['scheme']}://127.0.0.1:{twin.http}{job['metrics_path']}"
        status, body = scrape(url, credentials.read_text().strip())
        assert status == 200, body[:500]
        assert "pymotoros_" in body
        status, body = scrape(url, None)  # what an annotation-driven scrape would send
        assert status == 401, body[:500]


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


def test_a_twin_configured_like_a_pod_answers_its_per_pod_names(tmp_path: Path) -> None:
    """The headless Service gives every pod a name (``pymotoros-0.pymotoros``, in full
    ``pymotoros-0.pymotoros.NAMESPACE.svc.cluster.local``; docs/fleet.md): the
    StatefulSet's environment makes the twin answer to them (not only 403)."""
    env = {e["name"]: e["value"] for e in container()["env"] if "value" in e}
    service = manifests()["Service"]["metadata"]["name"]
    pod = manifests()["StatefulSet"]["metadata"]["name"] + "-0"
    with container_sim(tmp_path, env | {"PYMOTOROS_SIM_HTTP_PORT": "0"}) as twin:
        url = f"http://127.0.0.1:{twin.http}/api/state"
        for name in (f"{pod}.{service}", f"{pod}.{service}.robots.svc.cluster.local"):
            status, body = scrape_as(url, twin.token, f"{name}:8080")
            assert status == 200, f"{name}: {body[:500]}"
        status, body = scrape_as(url, twin.token, "rebind.attacker.example:8080")
        assert status == 403, body[:500]


def scrape_as(url: str, token: str, host: str) -> tuple[int, str]:
    request = urllib.request.Request(  # noqa: S310 - loopback http
        url, headers={"Authorization": f"Bearer {token}", "Host": host}
    )
    try:
        with urllib.request.urlopen(request, timeout=SCRAPE_TIMEOUT_S) as reply:  # noqa: S310
            return reply.status, reply.read().decode()
    except urllib.error.HTTPError as exc:
        return exc.code, exc.read().decode()
