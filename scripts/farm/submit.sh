#!/usr/bin/env bash
# Submit a shot to Slurm: a job array whose tasks each render some frames of one tile
# (scripts/farm/task.sh, picked by SLURM_ARRAY_TASK_ID), then a job that runs after all of them
# succeeded (--dependency=afterok) to assemble the tiles, write a contact sheet and an MP4
# (scripts/farm/finish.sh). Every task renders with --resume: submitting the same shot again
# after a failure or a cancel renders only what is missing, and gives the same images.
#
#   scripts/farm/submit.sh --scene FILE --frames A-B[:STEP] --out DIR [--tiles N]
#       [--frames-per-task K] [--ext exr|png] [--fps F] [--threads T] [--spotshell PATH]
#       [--sbatch 'OPTIONS'] [-- render options (--method sorted, --size 3840x2160, ...)]
#
# Tasks: ceil(frames / K) x N; task I renders frames chunk I / N, tile I % N (tiles are bands of
# rows: render --tile). Outputs: DIR/frames/shot.%04d.EXT, DIR/contact.png, DIR/shot.mp4 (when
# ffmpeg is there), DIR/tiles/ (N > 1), DIR/logs/.
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
usage="usage: submit.sh --scene FILE --frames A-B[:STEP] --out DIR [--tiles N] [--frames-per-task K] [--ext exr|png] [--fps F] [--threads T] [--spotshell PATH] [--sbatch 'OPTIONS'] [-- render options]"
fail() {
  echo "submit.sh: $*" >&2
  exit 2
}
scene='' frames='' out='' tiles=1 per_task=8 ext=exr fps=24 threads=2 sbatch_options=''
spotshell=$(command -v spotshell || echo "$here/../../build/spotshell")
while [ $# -gt 0 ]; do
  case $1 in
    --scene) scene=${2:-} ;;
    --frames) frames=${2:-} ;;
    --out) out=${2:-} ;;
    --tiles) tiles=${2:-} ;;
    --frames-per-task) per_task=${2:-} ;;
    --ext) ext=${2:-} ;;
    --fps) fps=${2:-} ;;
    --threads) threads=${2:-} ;;
    --spotshell) spotshell=${2:-} ;;
    --sbatch) sbatch_options=${2:-} ;;
    --) shift; break ;;
    -h|--help) echo "$usage"; exit 0 ;;
    *) fail "unknown option '$1' ($usage)" ;;
  esac
  [ $# -ge 2 ] || fail "$1 needs a value"
  shift 2
done
if ! command -v sbatch >/dev/null; then
  fail "sbatch not found: install Slurm's client and point it at your cluster (Debian/Ubuntu: apt-get install slurm-client; a one-machine cluster: apt-get install slurm-wlm munge, see README 'Shots on a farm')"
fi
[ -n "$scene" ] && [ -n "$frames" ] && [ -n "$out" ] || fail "$usage"
[ -f "$scene" ] || fail "scene $scene: no such file"
[ -x "$spotshell" ] || fail "spotshell $spotshell is not an executable (give --spotshell PATH)"
[[ $frames =~ ^([0-9]+)-([0-9]+)(:([0-9]+))?$ ]] || fail "--frames '$frames' must be A-B or A-B:STEP"
first=${BASH_REMATCH[1]} last=${BASH_REMATCH[2]} step=${BASH_REMATCH[4]:-1}
[ "$step" -ge 1 ] && [ "$first" -le "$last" ] || fail "--frames '$frames': A <= B and STEP >= 1"
[[ $tiles =~ ^[0-9]+$ ]] && [ "$tiles" -ge 1 ] || fail "--tiles '$tiles' must be a count >= 1"
[[ $per_task =~ ^[0-9]+$ ]] && [ "$per_task" -ge 1 ] || fail "--frames-per-task '$per_task' must be >= 1"
[[ $threads =~ ^[0-9]+$ ]] && [ "$threads" -ge 1 ] || fail "--threads '$threads' must be >= 1"
[ "$ext" = exr ] || [ "$ext" = png ] || fail "--ext '$ext' must be exr or png"
count=$(((last - first) / step + 1))
tasks=$(((count + per_task - 1) / per_task * tiles))
mkdir -p "$out/logs"
scene=$(cd "$(dirname "$scene")" && pwd)/$(basename "$scene")
out=$(cd "$out" && pwd)
spotshell=$(cd "$(dirname "$spotshell")" && pwd)/$(basename "$spotshell")
name=spot-$(basename "$scene" .json)
# shellcheck disable=SC2086 # the extra sbatch options are split as the user wrote them
array=$(sbatch --parsable --array="0-$((tasks - 1))" --job-name "$name" \
  --cpus-per-task="$threads" --output "$out/logs/task-%A_%a.log" \
  --export=ALL,LP_NUM_THREADS="$threads" $sbatch_options \
  "$here/task.sh" "$spotshell" "$scene" "$frames" "$tiles" "$per_task" "$out" "$ext" \
  --threads "$threads" "$@")
array=${array%%;*}
# shellcheck disable=SC2086
finish=$(sbatch --parsable --dependency="afterok:$array" --job-name "$name-finish" \
  --output "$out/logs/finish-%j.log" $sbatch_options \
  "$here/finish.sh" "$spotshell" "$frames" "$tiles" "$out" "$ext" "$fps")
finish=${finish%%;*}
echo "submitted array $array ($tasks tasks: $count frames, $tiles tiles, $per_task frames a task) and finish job $finish; outputs in $out"
