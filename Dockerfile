# One pymotoros twin per container (issue 13): run a fleet with the tools you already
# have (docker compose, a CI service container, a Kubernetes Deployment: deploy/k8s/),
# one twin each.
#
#   docker build -t pymotoros:0.1.0 .
#   export PYMOTOROS_TOKEN="$(python3 -c 'import secrets; print(secrets.token_urlsafe(32))')"
#   docker run --rm -e PYMOTOROS_TOKEN -p 50240-50242:50240-50242 -p 8080:8080 pymotoros:0.1.0
#   docker run --rm -e PYMOTOROS_TOKEN -v $PWD/examples/cells:/cells pymotoros:0.1.0 --config /cells/hc10_yrc1000.toml
#   docker run --rm -e PYMOTOROS_TOKEN -e PYMOTOROS_SIM_HTTP_PORT=9090 -p 9090:9090 pymotoros:0.1.0
#
# The ready line (`pymotoros sim ready motion=... state=... io=... http=...`) is the
# first line on stdout; GET /healthz (never guarded) is the health check, on the control
# API's port: PYMOTOROS_SIM_HTTP_PORT, read by `pymotoros sim` and the HEALTHCHECK alike
# (change the port with it, not with --http-port, or the health check asks the old one).
# `--host 0.0.0.0`: a container's loopback is unreachable from `docker run -p`, so the
# twin listens on every interface of its own network namespace. The control API (E-stop,
# modes, forced IO, the pendant's buttons) then needs a token (issue 23): the container
# refuses to start without PYMOTOROS_TOKEN (or --token), naming it; every /api route,
# /metrics and /ws/state take `Authorization: Bearer TOKEN`. The MotoROS ports stay open,
# as on a real controller: publish them only where you trust the network.
# The control API answers to its own names (localhost, the container's host name, any IP
# address) and refuses other Host headers with 403 (DNS rebinding). Reached under another
# name (a compose service name such as `http://twin-a:8080` from a sibling container, a
# Kubernetes Service), allow it: -e PYMOTOROS_SIM_ALLOWED_HOST="twin-a twin-b" (names
# separated by spaces; `.example.com` allows every name under it).
# Linted by hadolint and checked against the CLI by tests/test_dockerfile.py.
FROM python:3.11-slim

WORKDIR /opt/pymotoros
COPY pyproject.toml README.md ./
COPY src ./src
RUN python -m pip install --no-cache-dir . \
    && rm -rf /opt/pymotoros/src

# nobody (65534 in Debian): numeric, so the runtime need not resolve the name (DL3066)
USER 65534:65534
ENV PYMOTOROS_SIM_HTTP_PORT=8080
EXPOSE 50240 50241 50242 8080
HEALTHCHECK --interval=10s --timeout=3s --start-period=20s \
    CMD ["python", "-c", "import os, urllib.request; urllib.request.urlopen('http://127.0.0.1:%s/healthz' % os.environ['PYMOTOROS_SIM_HTTP_PORT'], timeout=2)"]
ENTRYPOINT ["pymotoros", "sim", "--host", "0.0.0.0"]
