#!/usr/bin/env bash
# All the tests: the Rust workspace, then the Python package (python/test.sh). The README's
# test command; .ci/run calls it after the formatting, lint and doc checks.
#
# The Rust tests run in the release profile: the lamdyn binary they build
# (target/release/lamdyn) is the one the Python tests compare with, so the optimised
# dependency tree is compiled once instead of once for tests and once for the binary (about
# 5 of CI's minutes on 2 cores). `cargo test` alone still works, in the test profile.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo test --workspace --release
LAMDYN_BIN="$PWD/target/release/lamdyn" python/test.sh
