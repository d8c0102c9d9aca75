#!/usr/bin/env bash
# README's first command: install dependencies, build, run the default job.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh
mkdir -p out
# The default job: the fur preset's impulses on the Stanford bunny.
build/spotshell impulses --mesh presets/meshes/bunny.ply --preset presets/fur.json \
  --out out/fur-bunny-impulses.ply
