# One pymotoros twin per container (issue 13): run a fleet with the tools you already
# have (docker compose, a CI service container, a Kubernetes Deployment), one twin each.
#
#   docker build -t pymotoros .
#   docker run --rm -p 50240-50242:50240-50242 -p 8080:8080 pymotoros
#   docker run --rm -v $PWD/examples/cells:/cells pymotoros --config /cells/hc10_yrc1000.toml
#
# The ready line (`pymotoros sim ready motion=... state=... io=... http=...`) is the
# first line on stdout; the control API's GET /api/state is the health check.
# `--host 0.0.0.0`: a container's loopback is unreachable from `docker run -p`, so the
# twin listens on every interface of its own network namespace (the sim warns: the
# control API has no authentication; publish its port only where you trust the network).
# Linted by hadolint and checked against the CLI by tests/test_dockerfile.py.
FROM python:3.11-slim

WORKDIR /opt/pymotoros
COPY pyproject.toml README.md ./
COPY src ./src
RUN python -m pip install --no-cache-dir . \
    && rm -rf /opt/pymotoros/src

# nobody (65534 in Debian): numeric, so the runtime need not resolve the name (DL3066)
USER 65534:65534
EXPOSE 50240 50241 50242 8080
HEALTHCHECK --interval=10s --timeout=3s --start-period=20s \
    CMD ["python", "-c", "import urllib.request; urllib.request.urlopen('http://127.0.0.1:8080/api/state', timeout=2)"]
ENTRYPOINT ["pymotoros", "sim", "--host", "0.0.0.0"]
