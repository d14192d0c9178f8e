#!/usr/bin/env bash
# `make demo`: renders the reference experiment's six temperature steps as H.264 videos with exact
# ground truth, measures every frame, and prints each step's mean effective diameter next to the truth.
# Usage: scripts/demo.sh path/to/clogscope [output dir]
set -euo pipefail
bin=${1:?usage: demo.sh path/to/clogscope [out dir]}
out=${2:-demo-out}
mkdir -p "$out/videos"
temps=(220 210 200 190 180 170)
diams=(400.0 396.9 390.1 381.3 365.9 345.4)   # µm, the reference study's means
frames=50
bias=0.4   # the rendered optics' edge bias, px: objects look 0.4 px wider than width/scale
echo "Rendering five pin gauges 300..500 µm (3 µm/px, edge bias $bias px) to $out/pins"
mkdir -p "$out/pins"
echo "image,diameter_um,tolerance_um" > "$out/pins/pins.csv"
for d in 300 350 400 450 500; do
  "$bin" render --target pin --strand-width-um $d --edge-bias-px $bias --tilt-deg 1.5 \
    --out "$out/pins/pin$d" --seed $d 2>/dev/null
  echo "pin$d/frame_000000.png,$d,0.5" >> "$out/pins/pins.csv"
done
echo "Calibrating (clogscope calibrate --pins)"
"$bin" calibrate --pins "$out/pins/pins.csv" --out "$out/calibration.yaml" 2>/dev/null | head -3
echo
echo "Rendering 6 steps x $frames frames (1280x720, width jitter 2 µm, sway 0.3°) to $out/videos"
for i in "${!temps[@]}"; do
  "$bin" render --out "$out/videos/step$((i + 1))_${temps[$i]}C.mp4" --frames $frames \
    --strand-width-um "${diams[$i]}" --width-jitter-um 2 --sway-deg 0.3 --highlight \
    --gradient 0.2 --edge-bias-px $bias --seed $((i + 1)) 2>/dev/null
done
echo "Measuring (clogscope measure --calib)"
"$bin" measure "$out"/videos/step*.mp4 --calib "$out/calibration.yaml" --out-frames "$out/frames.csv" \
  --overlay "$out/overlays"
echo
echo "Effective nozzle diameter per step (mean of the valid frames):"
# Per-step means from frames.csv beside the per-frame truth JSON (a stand-in until 'clogscope run').
for i in "${!temps[@]}"; do
  video="$out/videos/step$((i + 1))_${temps[$i]}C.mp4"
  truth_mean=$(grep -o '"width_um": [0-9.]*' "${video%.mp4}.truth.json" | awk '{s += $2; n++} END {printf "%.3f", s / n}')
  awk -F, -v src="$video" -v t="${temps[$i]}" -v nominal="${diams[$i]}" -v tm="$truth_mean" '
    /^#/ || NR == 0 { next }
    $1 == src && $4 == 1 { s += $7; ss += $7 * $7; n++ }
    END {
      m = s / n; sd = sqrt(ss / n - m * m)
      printf "  %3d °C  n=%2d  measured %7.2f ± %.2f µm   truth (frame mean) %7.2f µm   error %+5.2f µm   nominal %6.1f µm\n",
        t, n, m, sd / sqrt(n), tm, m - tm, nominal
    }' "$out/frames.csv"
done
echo
echo "Per-frame results: $out/frames.csv   overlays: $out/overlays/"
