#!/usr/bin/env bash
# README's second command (and CI's): make sure the build is current, then run the whole test
# suite through ctest.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh
ctest --test-dir build --output-on-failure -j2 "$@"
