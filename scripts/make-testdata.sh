#!/usr/bin/env bash
# Regenerates the committed fixtures under testdata/ with the renderer (see testdata/README.md).
# Usage: scripts/make-testdata.sh [path/to/clogscope]
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${1:-build/bin/clogscope}
common=(--size 640x360 --tip-x-px 320 --tip-y-px 100)
mkdir -p testdata/frames testdata/video
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
render_png() {  # name, options…
  local name=$1; shift
  "$bin" render --out "$tmp/$name" --truth "testdata/frames/$name.json" "${common[@]}" "$@"
  mv "$tmp/$name/frame_000000.png" "testdata/frames/$name.png"
}
render_png bright_tilt5 --tilt-deg 5 --seed 101
render_png silhouette_tilt-12 --tilt-deg -12 --silhouette --highlight --gradient 0.3 --blur-px 2.5 --seed 102
render_png colour_bed --colour --bed --tilt-deg 3 --seed 103
"$bin" render --out testdata/video/jitter_sway.mp4 --frames 25 --width-jitter-um 3 --sway-deg 0.5 \
  "${common[@]}" --seed 104
