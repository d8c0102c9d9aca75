#!/usr/bin/env bash
# README's first command: install dependencies, build, run the default job.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
bash scripts/build.sh
mkdir -p out
# The default job: the furry bunny rendered by render's default, the balanced quality
# (splat/quality.h: the `sorted` splatting renderer; Vulkan on the GPU, or on the CPU through
# lavapipe).
build/spotshell render --scene presets/scenes/fur-bunny.json --size 640x480 \
  --out out/fur-bunny.png
echo "image: $(pwd)/out/fur-bunny.png"
