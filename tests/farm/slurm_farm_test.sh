#!/usr/bin/env bash
# The farm test (ctest label `farm`): a shot rendered by a real Slurm job array is the shot one
# local process renders, bit for bit, and stays so when a task is cancelled mid-render and the
# shot is submitted again (--resume).
#   1. A one-node Slurm on loopback (slurm_cluster.sh: its own munged, slurmctld, slurmd,
#      slurm.conf in a temporary folder; stopped by the EXIT trap whatever happens).
#   2. One local process renders the shot (8 frames of an animated scene, whole).
#   3. scripts/farm/submit.sh: 4 tasks over 8 frames and 4 tiles (each task one tile of the 8
#      frames), then the finish job assembles the tiles and writes the contact sheet. Every frame
#      must be the local one's pixels exactly (idiff with zero tolerance), the sheet there, and
#      the MP4 of 8 frames where ffmpeg is installed (scripts/install-deps.sh installs it).
#   4. The same shot into a fresh folder, its frames slowed (--repeat: warm frames that change no
#      pixel); task 1 is cancelled (scancel) after its first tile and before its last: no file
#      it left under a final name is partial, the finish job never runs. Submitted again: only
#      the missing tiles render, every frame is again the local one's, and the finish job
#      deleted the temporary a killed writer leaves.
# It cannot skip: without root or Slurm it fails, saying what is missing.
#   slurm_farm_test.sh SPOTSHELL SOURCE_DIR
set -euo pipefail
spotshell=$1 source=$2
fail() {
  echo "FAIL: $*" >&2
  exit 1
}
[ "$(id -u)" = 0 ] || fail "the farm test starts slurmctld, slurmd and munged as root: run it as root (CI does)"
for tool in munged slurmctld slurmd sbatch squeue scancel sinfo idiff oiiotool; do
  command -v "$tool" >/dev/null ||
    fail "$tool not found: scripts/install-deps.sh installs slurm-wlm, munge and openimageio-tools"
done
start=$(date +%s)
work=$(mktemp -d /tmp/spot-farm.XXXXXX)
# shellcheck source=slurm_cluster.sh
source "$source/tests/farm/slurm_cluster.sh"
cleanup() {
  local rc=$?
  [ -n "${SLURM_CONF:-}" ] && scancel --quiet -u root 2>/dev/null || true
  cluster_stop
  if [ $rc -eq 0 ]; then rm -rf "$work"; else echo "(kept $work)" >&2; fi
}
trap cleanup EXIT
cluster_start "$work/cluster" 2

scene=$source/examples/animated/tail-fur.json
render=(--size 128x96 --method sorted)
export LP_NUM_THREADS=1

# Wait (at most $1 seconds) until none of the jobs $2... is in the queue.
wait_jobs() {
  local limit=$1
  shift
  local ids
  ids=$(IFS=,; echo "$*")
  timeout "$limit" bash -c "while squeue -h -j '$ids' 2>/dev/null | grep -q .; do sleep 0.5; done" ||
    fail "jobs $ids still queued after ${limit}s: $(squeue 2>&1 | tr '\n' ' ')"
}
# The job ids in submit.sh's line "submitted array A (...) and finish job F; ...".
submit() {
  local line
  line=$("$source/scripts/farm/submit.sh" --spotshell "$spotshell" --scene "$scene" --frames 0-7 \
    --tiles 4 --frames-per-task 8 --threads 1 --out "$1" --ext exr -- "${render[@]}" "${@:2}")
  echo "$line" >&2
  array=$(sed -n 's/^submitted array \([0-9]*\) .*/\1/p' <<<"$line")
  finish=$(sed -n 's/.* and finish job \([0-9]*\);.*/\1/p' <<<"$line")
  [ -n "$array" ] && [ -n "$finish" ] || fail "submit.sh said: $line"
}
# Every frame of the shot in $1/frames holds the local render's pixels exactly.
expect_shot() {
  local f
  for f in 0 1 2 3 4 5 6 7; do
    local name
    name=$(printf 'shot.%04d.exr' "$f")
    [ -f "$1/frames/$name" ] || fail "$1/frames/$name is missing"
    idiff -fail 0 -warn 0 "$work/local/$name" "$1/frames/$name" >/dev/null ||
      fail "$1/frames/$name differs from the local render's $name"
  done
  echo "ok: the 8 frames in $1 are the local render's, bit for bit"
}

# The shot as one local process renders it.
mkdir -p "$work/local"
"$spotshell" render --scene "$scene" "${render[@]}" --frames 0-7 --out "$work/local/shot.%04d.exr" \
  >/dev/null
# The frames differ (the scene moves), so a mixed-up frame cannot pass.
if idiff -fail 0 -warn 0 "$work/local/shot.0000.exr" "$work/local/shot.0007.exr" >/dev/null; then
  fail "frames 0 and 7 of the local shot are the same: the scene does not move"
fi

# submit.sh without sbatch says how to install Slurm, in one line, exit 2.
mkdir -p "$work/nosbatch"
for tool in bash dirname basename cat; do ln -s "$(command -v "$tool")" "$work/nosbatch/$tool"; done
set +e
message=$(PATH=$work/nosbatch "$source/scripts/farm/submit.sh" --scene "$scene" --frames 0-7 \
  --out "$work/x" 2>&1)
code=$?
set -e
[ $code = 2 ] && [ "$(wc -l <<<"$message")" = 1 ] && grep -q "apt-get install" <<<"$message" ||
  fail "submit.sh without sbatch: exit $code, said: $message"

# Each bad input is one line and exit 2, and leaves nothing behind: a machine with sbatch but no
# cluster, options the cluster refuses, an --out in a folder that is not there, frames outside
# the clip.
refused() { # refused WHAT EXPECTED-TEXT submit.sh-arguments...
  local what=$1 expect=$2 message code
  shift 2
  set +e
  message=$("$source/scripts/farm/submit.sh" --spotshell "$spotshell" --scene "$scene" "$@" 2>&1)
  code=$?
  set -e
  [ $code = 2 ] && [ "$(wc -l <<<"$message")" = 1 ] && grep -q -- "$expect" <<<"$message" ||
    fail "submit.sh with $what: exit $code, said: $message"
  [ ! -e "$work/bad" ] || fail "submit.sh with $what left $work/bad behind"
  echo "ok: $what: $message"
}
SLURM_CONF=$work/no-cluster/slurm.conf refused "no cluster" "no Slurm cluster answers" \
  --frames 0-7 --out "$work/bad"
refused "a refused sbatch option" "the cluster refuses" --frames 0-7 --out "$work/bad" \
  --sbatch '--partition=nosuch'
refused "a missing shared folder" "does not exist" --frames 0-7 --out "$work/bad/shots/tail"
refused "frames outside the clip" "outside the scene's clip: frames 0-48" --frames 0-100 \
  --out "$work/bad"
# Frames count from the clip's start: the character's clip is Blender's frames 1 to 25.
refused "frame 0 of a clip from frame 1" "outside the scene's clip: frames 1-25" \
  --scene "$source/examples/character/character-fur.json" --frames 0-3 --out "$work/bad"

# README's example runs as written on this cluster (its --out in a shared folder made here, and
# --test-only: checked and accepted, nothing submitted).
readme=$(awk '/^scripts\/farm\/submit.sh/,/method sorted$/' "$source/README.md" | tr -d '\\\n')
[[ $readme == *"--sbatch '--mem=4G'"* ]] || fail "README's submit.sh example not found: $readme"
mkdir -p "$work/shared/shots"
readme=${readme//\/shared\/shots\/bunny/$work/shared/shots/bunny}
readme=${readme/scripts\/farm\/submit.sh/scripts\/farm\/submit.sh --spotshell '$spotshell' --test-only}
message=$(cd "$source" && eval "$readme" 2>&1) ||
  fail "README's example ($readme) was refused: $message"
echo "ok: README's example: $message"

# 3. The shot on the farm.
submit "$work/farm1"
wait_jobs 150 "$array" "$finish"
[ "$(ls "$work/farm1/tiles" | wc -l)" = 32 ] || fail "farm1: $(ls "$work/farm1/tiles" | wc -l) tiles, not 32"
expect_shot "$work/farm1"
[ -f "$work/farm1/contact.png" ] || fail "farm1: no contact sheet"
if command -v ffmpeg >/dev/null; then
  frames=$(ffprobe -v error -count_frames -select_streams v:0 -show_entries stream=nb_read_frames \
    -of csv=p=0 "$work/farm1/shot.mp4" 2>&1) || fail "farm1: no readable MP4 ($frames)"
  [ "$frames" = 8 ] || fail "farm1: the MP4 has $frames frames, not 8"
fi
echo "ok: farm1 in $(($(date +%s) - start)) s"

# 4. A task cancelled mid-render, then the shot submitted again.
slow=(--repeat 12) # warm frames after each frame: slower tasks, the same pixels
submit "$work/farm2" "${slow[@]}"
tile1() { find "$work/farm2/tiles" -maxdepth 1 -name 'shot.*.tile1.exr' 2>/dev/null | wc -l; }
timeout 120 bash -c "until [ -n \"\$(find '$work/farm2/tiles' -maxdepth 1 -name 'shot.*.tile1.exr' 2>/dev/null)\" ]; do sleep 0.05; done" ||
  fail "task 1 wrote no tile in 120 s"
scancel "${array}_1"
timeout 60 bash -c "while squeue -h -j '${array}_1' 2>/dev/null | grep -q .; do sleep 0.2; done" ||
  fail "task ${array}_1 did not end after scancel"
done_before=$(tile1)
[ "$done_before" -ge 1 ] && [ "$done_before" -lt 8 ] ||
  fail "task 1 had written $done_before of its 8 tiles when cancelled: not mid-render"
for file in "$work/farm2/tiles"/shot.*.exr; do
  oiiotool --info "$file" >/dev/null 2>&1 || fail "$file, left by the cancelled task, is partial"
done
# The finish job waits on a task that failed: it never runs.
wait_jobs 120 "$array"
scancel "$finish" 2>/dev/null || true
[ ! -e "$work/farm2/frames/shot.0000.exr" ] || fail "the finish job ran although task 1 was cancelled"
echo "ok: task 1 cancelled after $done_before of 8 tiles; every file it left is whole"
# What a task killed while writing (SIGKILL) leaves: its hidden temporary, never under a final
# name; the finish job deletes it.
head -c 1000 /dev/urandom >"$work/farm2/tiles/.shot.0003.tile1.tmp5eed.exr"
submit "$work/farm2" "${slow[@]}"
wait_jobs 150 "$array" "$finish"
grep -q "already there" "$work/farm2/logs/task-${array}_1.log" ||
  fail "the resubmitted task 1 rendered everything again: $(cat "$work/farm2/logs/task-${array}_1.log")"
expect_shot "$work/farm2"
[ -z "$(find "$work/farm2/tiles" -name '.*.tmp*')" ] || fail "farm2: temporaries left in tiles/"
echo "ok: the farm test passed in $(($(date +%s) - start)) s"
