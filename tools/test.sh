#!/usr/bin/env bash
# All the tests: the Rust workspace, then the Python package (python/test.sh). The README's
# test command; .ci/run calls it after the formatting, lint and doc checks.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo test --workspace
python/test.sh
