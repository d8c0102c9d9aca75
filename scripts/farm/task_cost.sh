#!/usr/bin/env bash
# The cost of a farm task (README, "Shots on a farm"): the wall time of a one-frame task and of
# an (N+1)-frame task of the same scene, cold (MESA_SHADER_CACHE_DISABLE=true: every pipeline
# compiled) and warm (a warmed MESA_SHADER_CACHE_DIR), R runs each, medians. The fixed cost is
# the one-frame task less one further frame; "frames" is how many further frames it is worth.
#
#   scripts/farm/task_cost.sh [SPOTSHELL] [SCENE]   (env: SIZES="640x480 1920x1080", N=10, R=3,
#                                                    EXTRA="--method sorted", LP_NUM_THREADS=2)
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
spotshell=${1:-$here/../../build/spotshell}
scene=${2:-$here/../../presets/scenes/fur-bunny.json}
export LP_NUM_THREADS=${LP_NUM_THREADS:-2}
n=${N:-10} runs=${R:-3}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
now() { date +%s.%N; }
median() { sort -g | awk '{ v[NR] = $1 } END { print v[int((NR + 1) / 2)] }'; }
start=()
for ((r = 0; r < 5; ++r)); do
  t0=$(now); "$spotshell" --help >/dev/null; t1=$(now)
  start+=("$(echo "$t1 - $t0" | bc -l)")
done
printf 'process start (spotshell --help): %.3f s\n' "$(printf '%s\n' "${start[@]}" | median)"
for size in ${SIZES:-640x480 1920x1080}; do
  # shellcheck disable=SC2086 # EXTRA: options as the user wrote them
  render() { "$@" "$spotshell" render --scene "$scene" --size "$size" ${EXTRA:-} "${args[@]}" >/dev/null; }
  args=(--frames 0-0 --out "$work/w.%04d.exr")
  render env MESA_SHADER_CACHE_DIR="$work/cache" # warms the cache
  for mode in cold warm; do
    if [ $mode = cold ]; then cache=MESA_SHADER_CACHE_DISABLE=true; else cache=MESA_SHADER_CACHE_DIR=$work/cache; fi
    ones=() pers=() firsts=() loads=()
    for ((r = 0; r < runs; ++r)); do
      args=(--frames 0-0 --out "$work/a.%04d.exr" --stats "$work/one.json")
      t0=$(now); render env "$cache"; t1=$(now)
      args=(--frames "0-$n" --out "$work/b.%04d.exr")
      render env "$cache"; t2=$(now)
      ones+=("$(echo "$t1 - $t0" | bc -l)")
      pers+=("$(echo "(($t2 - $t1) - ($t1 - $t0)) / $n" | bc -l)")
      firsts+=("$(python3 -c "import json, sys; print(json.load(open(sys.argv[1]))['first_frame']['wall_ms'] / 1000)" "$work/one.json")")
      loads+=("$(python3 -c "import json, sys; print(json.load(open(sys.argv[1]))['generate_seconds'])" "$work/one.json")")
    done
    one=$(printf '%s\n' "${ones[@]}" | median)
    per=$(printf '%s\n' "${pers[@]}" | median)
    printf '%s %s: one-frame task %.2f s (scene load and cells %.2f s, first frame %.2f s); each further frame %.3f s; fixed %.2f s = %.1f frames\n' \
      "$size" $mode "$one" "$(printf '%s\n' "${loads[@]}" | median)" \
      "$(printf '%s\n' "${firsts[@]}" | median)" "$per" "$(echo "$one - $per" | bc -l)" \
      "$(echo "($one - $per) / $per" | bc -l)"
  done
done
