#!/usr/bin/env bash
# One task of a shot (scripts/farm/submit.sh makes the array): task I renders frame chunk
# I / TILES (PER_TASK frames of the range) of tile I % TILES, with --resume, so a task that was
# killed, or run twice, completes the shot identically. Any scheduler runs it the same way:
# Slurm gives the task index in SLURM_ARRAY_TASK_ID, others as FARM_TASK_ID (OpenCue's
# CUE_IFRAME, Deadline's <STARTFRAME>: see README, "Shots on a farm").
#
#   task.sh SPOTSHELL SCENE FRAMES TILES PER_TASK OUT_DIR EXT [render options...]
#     FRAMES A-B[:STEP]; TILES >= 1; PER_TASK >= 1 frames; EXT exr | png.
# Outputs: OUT_DIR/frames/shot.%04d.EXT with one tile, else OUT_DIR/tiles/shot.%04d.tileT.EXT;
# the pipeline cache in OUT_DIR/cache (unless SPOT_PIPELINE_CACHE names another folder).
set -euo pipefail
if [ $# -lt 7 ]; then
  echo "usage: task.sh SPOTSHELL SCENE FRAMES TILES PER_TASK OUT_DIR EXT [render options...]" >&2
  exit 2
fi
spotshell=$1 scene=$2 frames=$3 tiles=$4 per_task=$5 out=$6 ext=$7
shift 7
task=${SLURM_ARRAY_TASK_ID:-${FARM_TASK_ID:-}}
if ! [[ $task =~ ^[0-9]+$ ]]; then
  echo "task.sh: no task index: set SLURM_ARRAY_TASK_ID (sbatch --array) or FARM_TASK_ID" >&2
  exit 2
fi
if ! [[ $frames =~ ^([0-9]+)-([0-9]+)(:([0-9]+))?$ ]]; then
  echo "task.sh: frames '$frames' must be A-B or A-B:STEP" >&2
  exit 2
fi
first=${BASH_REMATCH[1]} last=${BASH_REMATCH[2]} step=${BASH_REMATCH[4]:-1}
chunk=$((task / tiles)) tile=$((task % tiles))
a=$((first + chunk * per_task * step))
b=$((a + (per_task - 1) * step))
if [ "$b" -gt "$last" ]; then b=$last; fi
if [ "$a" -gt "$last" ]; then
  echo "task.sh: task $task is past the shot ($frames, $tiles tiles, $per_task frames a task)" >&2
  exit 2
fi
if [ "$tiles" -gt 1 ]; then
  dir=$out/tiles
  pattern=$dir/shot.%04d.tile$tile.$ext
  tile_option=(--tile "$tile/$tiles")
else
  dir=$out/frames
  pattern=$dir/shot.%04d.$ext
  tile_option=()
fi
mkdir -p "$dir"
# The shot's pipeline cache (README, "Shots on a farm"): in its folder, so that the tasks after
# the first make their pipelines from it (one file per device kind; written atomically).
export SPOT_PIPELINE_CACHE=${SPOT_PIPELINE_CACHE:-$out/cache}
echo "task $task on $(hostname -s): frames $a-$b:$step, tile $tile of $tiles"
exec "$spotshell" render --scene "$scene" --frames "$a-$b:$step" "${tile_option[@]}" \
  --out "$pattern" --resume "$@"
