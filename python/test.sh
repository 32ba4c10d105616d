#!/usr/bin/env bash
# The Python package's tests as on a fresh machine: a virtual environment, the package built
# and installed by pip exactly as the README says (`pip install "./python[test]"`: maturin
# builds the abi3 wheel), the lamdyn binary the results are compared with, then pytest.
# LAMDYN_VENV chooses the environment's folder (default target/python-venv); LAMDYN_BIN the
# lamdyn binary (default: target/release/lamdyn, built here). Arguments go to pytest
# (`python/test.sh -k killed`).
set -euo pipefail
cd "$(dirname "$0")/.."
VENV=${LAMDYN_VENV:-target/python-venv}
python3 -m venv "$VENV"
"$VENV/bin/python" -m pip install -q --upgrade pip
"$VENV/bin/python" -m pip install -q "./python[test]"
# The binary the results are compared with: LAMDYN_BIN where the caller built it (tools/test.sh
# takes the one its release-profile tests built), else target/release/lamdyn, built here.
if [ -z "${LAMDYN_BIN:-}" ]; then
    cargo build --release -p lamdyn
fi
"$VENV/bin/python" -m pytest python/tests -q -rA --durations=5 "$@"
