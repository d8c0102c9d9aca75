#!/usr/bin/env bash
# Submit a shot to Slurm: a job array whose tasks each render some frames of one tile
# (scripts/farm/task.sh, picked by SLURM_ARRAY_TASK_ID), then a job that runs after all of them
# succeeded (--dependency=afterok) to assemble the tiles, write a contact sheet and an MP4
# (scripts/farm/finish.sh). Every task renders with --resume: submitting the same shot again
# after a failure or a cancel renders only what is missing, and gives the same images.
#
#   scripts/farm/submit.sh --scene FILE --frames A-B[:STEP] --out DIR [--tiles N]
#       [--frames-per-task K] [--ext exr|png] [--fps F] [--threads T] [--spotshell PATH]
#       [--sbatch 'OPTIONS'] [--test-only] [-- render options (--method sorted, ...)]
#
# Tasks: ceil(frames / K) x N; task I renders frames chunk I / N, tile I % N (tiles are bands of
# rows: render --tile). Outputs: DIR/frames/shot.%04d.EXT, DIR/contact.png, DIR/shot.mp4 (when
# ffmpeg is there), DIR/tiles/ (N > 1), DIR/logs/. Frames are numbered as spotshell numbers them
# (frame f at f / fps, from the clip's start: spotshell info --scene FILE prints the range).
#
# Everything is checked before anything is made or submitted, each failure one line and exit 2,
# nothing left behind: sbatch there, a cluster that answers, DIR's folder there (a folder every
# node sees), the frames within the scene's clip, and the cluster accepting the job's options
# (sbatch --test-only with --sbatch's options). --test-only stops there: nothing is submitted.
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
usage="usage: submit.sh --scene FILE --frames A-B[:STEP] --out DIR [--tiles N] [--frames-per-task K] [--ext exr|png] [--fps F] [--threads T] [--spotshell PATH] [--sbatch 'OPTIONS'] [--test-only] [-- render options]"
fail() {
  echo "submit.sh: $*" >&2
  exit 2
}
scene='' frames='' out='' tiles=1 per_task=8 ext=exr fps=24 threads=2 sbatch_options='' test_only=0
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
    --test-only) test_only=1; shift; continue ;;
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
# The first line of a command's complaint, for one-line messages.
first_line() { tr -s '\n' '\n' | grep -v '^[[:space:]]*$' | head -n 1; }
# A cluster that answers (sbatch alone says nothing until it submits), within 10 s: without a
# configuration Slurm's tools retry for a minute.
if ! answer=$(timeout 10 sinfo -h -o %P 2>&1); then
  fail "no Slurm cluster answers (sinfo: $(first_line <<<"${answer:-no answer in 10 s}")): point SLURM_CONF at your cluster's slurm.conf, or start one (README 'Shots on a farm')"
fi
# The output's folder: every node writes there, so it must already be a shared folder; a
# missing one is not made here (it would be this machine's alone).
parent=$(dirname "$out")
[ -d "$parent" ] || fail "--out $out: its folder $parent does not exist (make it on a file system every node sees)"
# The frames within what the scene spans (spotshell's numbering: from the clip's start).
if span=$("$spotshell" info --scene "$scene" 2>&1); then
  if [[ $span =~ frames\ +([0-9-]+)-([0-9]+)\ at ]]; then
    lo=${BASH_REMATCH[1]} hi=${BASH_REMATCH[2]}
    [ "$first" -ge "$lo" ] && [ "$last" -le "$hi" ] ||
      fail "--frames '$frames' reaches outside the scene's clip: frames $lo-$hi"
  fi
else
  fail "scene $scene: $(first_line <<<"$span")"
fi
# The cluster takes the job as asked (memory, partition, time...): a test submission.
# shellcheck disable=SC2086 # the extra sbatch options are split as the user wrote them
if ! answer=$(timeout 30 sbatch --test-only --cpus-per-task="$threads" $sbatch_options --wrap true 2>&1); then
  fail "the cluster refuses the job's options (--cpus-per-task=$threads${sbatch_options:+ $sbatch_options}): $(first_line <<<"$answer")"
fi
count=$(((last - first) / step + 1))
tasks=$(((count + per_task - 1) / per_task * tiles))
if [ "$test_only" = 1 ]; then
  echo "test only: $tasks tasks ($count frames, $tiles tiles, $per_task frames a task) would be submitted; outputs in $out"
  exit 0
fi
# What this run makes, removed again if the submission fails.
made=()
[ -d "$out" ] || made+=("$out")
[ -d "$out/logs" ] || made+=("$out/logs")
undo() {
  local i
  for ((i = ${#made[@]} - 1; i >= 0; --i)); do rmdir "${made[i]}" 2>/dev/null || true; done
}
mkdir -p "$out/logs"
scene=$(cd "$(dirname "$scene")" && pwd)/$(basename "$scene")
out=$(cd "$out" && pwd)
spotshell=$(cd "$(dirname "$spotshell")" && pwd)/$(basename "$spotshell")
name=spot-$(basename "$scene" .json)
# shellcheck disable=SC2086 # the extra sbatch options are split as the user wrote them
if ! array=$(sbatch --parsable --array="0-$((tasks - 1))" --job-name "$name" \
  --cpus-per-task="$threads" --output "$out/logs/task-%A_%a.log" \
  --export=ALL,LP_NUM_THREADS="$threads" $sbatch_options \
  "$here/task.sh" "$spotshell" "$scene" "$frames" "$tiles" "$per_task" "$out" "$ext" \
  --threads "$threads" "$@" 2>&1); then
  undo
  fail "sbatch refused the array: $(first_line <<<"$array")"
fi
array=${array%%;*}
# shellcheck disable=SC2086
if ! finish=$(sbatch --parsable --dependency="afterok:$array" --job-name "$name-finish" \
  --output "$out/logs/finish-%j.log" $sbatch_options \
  "$here/finish.sh" "$spotshell" "$frames" "$tiles" "$out" "$ext" "$fps" 2>&1); then
  scancel "$array" 2>/dev/null || true
  undo
  fail "sbatch refused the finish job (array $array cancelled): $(first_line <<<"$finish")"
fi
finish=${finish%%;*}
echo "submitted array $array ($tasks tasks: $count frames, $tiles tiles, $per_task frames a task) and finish job $finish; outputs in $out"
