#!/usr/bin/env bash
# The suite against the newest releases of every dependency (not requirements/test.lock):
# a new virtual environment in a temporary directory, the README's plain install in it,
# then pytest. Run it now and then (and before regenerating the lock) to see a break
# like pytest-asyncio 1.x's loop-scope warning before a user does (docs/testing.md).
#
#   tools/test_newest.sh                          # the whole suite
#   tools/test_newest.sh tests/examples -x        # arguments go to pytest
#   WITH="pytest<9 pytest-asyncio==0.23.8" tools/test_newest.sh tests/examples
#                                                 # ... with some packages held back
#
# The environment is removed afterwards; KEEP_VENV=1 keeps it (its path is printed).
set -euo pipefail
cd "$(dirname "$0")/.."

venv_parent=$(mktemp -d "${TMPDIR:-/tmp}/pymotoros-newest.XXXXXX")
if [ -z "${KEEP_VENV:-}" ]; then
    trap 'rm -rf "$venv_parent"' EXIT
fi
"${PYTHON:-python3}" -m venv "$venv_parent/venv"
export VIRTUAL_ENV="$venv_parent/venv"
export PATH="$VIRTUAL_ENV/bin:$PATH"
echo "tools/test_newest.sh: new virtual environment $VIRTUAL_ENV" >&2

# the README's install, resolved afresh: the newest releases pyproject.toml allows
# (WITH, word-split on purpose, holds some back: requirement specifiers, no spaces inside)
# shellcheck disable=SC2086
python -m pip install --upgrade -e ".[test]" ${WITH:-}
python -m pip list --format=freeze | grep -iE '^(pytest|pytest-asyncio|pytest-xdist|hypothesis)==' >&2 || true
python -m pytest "$@"
