#!/usr/bin/env bash
# The shot's last job (after every task of the array succeeded): the tiles assembled into
# OUT_DIR/frames (spotshell assemble; frames already there are kept), a contact sheet
# OUT_DIR/contact.png (oiiotool --mosaic, at most 64 frames spread over the shot) and, when ffmpeg
# is there, OUT_DIR/shot.mp4 (both from 8-bit sRGB previews over black). Every output is written
# to a temporary name, then renamed; the temporaries killed tasks left are deleted.
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
# A task killed while writing (SIGKILL) leaves its hidden temporary beside the file it never
# renamed; every task of the shot has ended now, so none is being written.
find "$out/frames" "$out/tiles" -maxdepth 1 -name '.*.tmp*' -delete 2>/dev/null || true

command -v oiiotool >/dev/null || {
  echo "finish: no oiiotool (apt-get install openimageio-tools): no contact sheet, no MP4"
  exit 0
}
# Previews: each frame as 8-bit sRGB colour over black (an EXR's premultiplied colour; a PNG's
# colour premultiplied on reading), what the sheet and the MP4 are made of (ffmpeg's own EXR
# reader is not trusted with every EXR).
rm -rf "$out/.previews" && mkdir -p "$out/.previews"
previews=()
for frame in "${made[@]}"; do
  preview=$out/.previews/$(basename "${frame%.*}").png
  convert=()
  [ "$ext" = exr ] && convert=(--colorconvert linear sRGB)
  oiiotool "$frame" "${convert[@]}" --ch R,G,B -d uint8 -o "$preview"
  previews+=("$preview")
done

# The contact sheet: up to 64 frames, evenly spread, 8 to a row, each fit in 256x256.
n=${#previews[@]}
pick=$((n > 64 ? 64 : n))
sheet=()
for ((i = 0; i < pick; ++i)); do
  sheet+=("${previews[$((i * n / pick))]}" --fit 256x256)
done
columns=$((pick < 8 ? pick : 8))
rows=$(((pick + columns - 1) / columns))
oiiotool "${sheet[@]}" --mosaic:pad=2 "${columns}x${rows}" -d uint8 -o "$out/.contact.tmp.png"
mv -f "$out/.contact.tmp.png" "$out/contact.png"
echo "finish: wrote $out/contact.png ($pick frames)"

if command -v ffmpeg >/dev/null; then
  ffmpeg -loglevel error -y -framerate "$fps" -pattern_type glob -i "$out/.previews/shot.*.png" \
    -vf "pad=ceil(iw/2)*2:ceil(ih/2)*2" -c:v libx264 -pix_fmt yuv420p -f mp4 "$out/.shot.tmp.mp4"
  mv -f "$out/.shot.tmp.mp4" "$out/shot.mp4"
  echo "finish: wrote $out/shot.mp4 ($n frames at $fps fps)"
else
  echo "finish: no ffmpeg: no MP4"
fi
rm -rf "$out/.previews"
