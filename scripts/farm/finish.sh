#!/usr/bin/env bash
# The shot's last job (after every task of the array succeeded): the tiles assembled into
# OUT_DIR/frames (spotshell assemble; frames already there are kept), a contact sheet
# OUT_DIR/contact.png (oiiotool --mosaic, at most 64 frames spread over the shot) and, when ffmpeg
# is there, OUT_DIR/shot.mp4. Every output is written to a temporary name, then renamed.
#
#   finish.sh SPOTSHELL FRAMES TILES OUT_DIR EXT FPS
set -euo pipefail
if [ $# -ne 6 ]; then
  echo "usage: finish.sh SPOTSHELL FRAMES TILES OUT_DIR EXT FPS" >&2
  exit 2
fi
spotshell=$1 frames=$2 tiles=$3 out=$4 ext=$5 fps=$6
if ! [[ $frames =~ ^([0-9]+)-([0-9]+)(:([0-9]+))?$ ]]; then
  echo "finish.sh: frames '$frames' must be A-B or A-B:STEP" >&2
  exit 2
fi
first=${BASH_REMATCH[1]} last=${BASH_REMATCH[2]} step=${BASH_REMATCH[4]:-1}
mkdir -p "$out/frames"
made=()
for ((f = first; f <= last; f += step)); do
  frame=$(printf '%s/frames/shot.%04d.%s' "$out" "$f" "$ext")
  if [ "$tiles" -gt 1 ] && [ ! -f "$frame" ]; then
    parts=()
    for ((t = 0; t < tiles; ++t)); do
      parts+=("$(printf '%s/tiles/shot.%04d.tile%d.%s' "$out" "$f" "$t" "$ext")")
    done
    "$spotshell" assemble "${parts[@]}" --out "$frame" >/dev/null
  fi
  made+=("$frame")
done
echo "finish: ${#made[@]} frames in $out/frames"

# The contact sheet: up to 64 frames, evenly spread, 8 to a row, each at most 256 pixels wide.
n=${#made[@]}
pick=$((n > 64 ? 64 : n))
sheet=()
for ((i = 0; i < pick; ++i)); do
  sheet+=("${made[$((i * n / pick))]}" --fit 256x256)
  [ "$ext" = exr ] && sheet+=(--colorconvert linear sRGB)
done
columns=$((pick < 8 ? pick : 8))
rows=$(((pick + columns - 1) / columns))
if command -v oiiotool >/dev/null; then
  oiiotool "${sheet[@]}" --mosaic:pad=2 "${columns}x${rows}" -d uint8 -o "$out/.contact.tmp.png"
  mv -f "$out/.contact.tmp.png" "$out/contact.png"
  echo "finish: wrote $out/contact.png ($pick frames)"
else
  echo "finish: no oiiotool (apt-get install openimageio-tools): no contact sheet"
fi

if command -v ffmpeg >/dev/null; then
  input=()
  [ "$ext" = exr ] && input=(-apply_trc iec61966_2_1)
  ffmpeg -loglevel error -y -framerate "$fps" -pattern_type glob "${input[@]}" \
    -i "$out/frames/shot.*.$ext" -vf "pad=ceil(iw/2)*2:ceil(ih/2)*2" -pix_fmt yuv420p \
    -f mp4 "$out/.shot.tmp.mp4"
  mv -f "$out/.shot.tmp.mp4" "$out/shot.mp4"
  echo "finish: wrote $out/shot.mp4"
else
  echo "finish: no ffmpeg: no MP4"
fi
