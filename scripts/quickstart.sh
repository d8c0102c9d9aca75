#!/usr/bin/env bash
# README's first command: install dependencies, build, run the default job.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh
mkdir -p out
# The default job: the furry bunny rendered by the converged reference, and its impulses.
build/spotshell impulses --mesh presets/meshes/bunny.ply --preset presets/fur.json \
  --out out/fur-bunny-impulses.ply
build/spotshell render --scene presets/scenes/fur-bunny.json --method reference \
  --out out/fur-bunny-reference.png
