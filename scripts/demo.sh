#!/usr/bin/env bash
# `make demo`: the built-in experiment, end to end. Renders five pin gauges and the reference
# experiment's six temperature steps (220 -> 170 °C) as H.264 videos with exact ground truth,
# writes a manifest, runs `clogscope run` on it (calibrate, measure, predict, summarise) and prints
# each step's diameter next to the truth.
# Usage: scripts/demo.sh path/to/clogscope [output dir]
set -euo pipefail
bin=${1:?usage: demo.sh path/to/clogscope [out dir]}
out=${2:-demo-out}
mkdir -p "$out/videos" "$out/pins"
temps=(220 210 200 190 180 170)
diams=(400.0 396.9 390.1 381.3 365.9 345.4)   # µm, the reference study's means
seconds=6
bias=0.4   # the rendered optics' edge bias, px: objects look 0.4 px wider than width/scale

echo "Rendering five pin gauges 300..500 µm and six ${seconds}-s 1280x720 H.264 step videos"
echo "(3 µm/px, edge bias $bias px, blur 1.5 px, noise 3, width jitter 2 µm, sway 0.3°) into $out/"
echo "image,diameter_um,tolerance_um" > "$out/pins/pins.csv"
for d in 300 350 400 450 500; do
  "$bin" render --target pin --strand-width-um $d --edge-bias-px $bias --tilt-deg 1.5 \
    --out "$out/pins/pin$d" --seed $d 2>/dev/null
  echo "pin$d/frame_000000.png,$d,0.5" >> "$out/pins/pins.csv"
done
{
  echo "# Built-in demo experiment (clogscope make demo)"
  echo "name: reference experiment (rendered)"
  echo "samples: 50"
  echo "settle_s: 1.0"
  echo "calibrate:"
  echo "  pins: pins/pins.csv"
  echo "extruder: direct-pla"
  echo "steps:"
} > "$out/experiment.yaml"
for i in "${!temps[@]}"; do
  video="videos/step$((i + 1))_${temps[$i]}C.mp4"
  "$bin" render --out "$out/$video" --frames $((seconds * 25)) --strand-width-um "${diams[$i]}" \
    --width-jitter-um 2 --sway-deg 0.3 --highlight --gradient 0.2 --edge-bias-px $bias \
    --seed $((i + 1)) 2>/dev/null
  echo "  - {step: $((i + 1)), temperature_c: ${temps[$i]}, video: $video}" >> "$out/experiment.yaml"
done

echo
echo "clogscope run $out/experiment.yaml --out $out/results"
"$bin" run "$out/experiment.yaml" --out "$out/results"

echo
echo "Against the truth (nominal: the rendered mean diameter; frames: the mean of the frames used):"
for i in "${!temps[@]}"; do
  step=$((i + 1))
  truth="$out/videos/step${step}_${temps[$i]}C.truth.json"
  # The truth JSON lists frames in order, each with its width_um; frames.csv says which were used.
  awk -F, -v step=$step -v nominal="${diams[$i]}" -v truth="$truth" '
    BEGIN {
      while ((getline line < truth) > 0) {
        if (line ~ /"frame":/) { gsub(/[^0-9]/, "", line); f = line }
        if (line ~ /"width_um":/ && f != "") { sub(/.*: */, "", line); sub(/,.*/, "", line); w[f] = line + 0; f = "" }
      }
    }
    /^#/ { next }
    $1 == step && $20 == 1 { s += w[$3]; n++ }
    END { printf "%d %.3f %d\n", step, n ? s / n : 0, n }' "$out/results/frames.csv"
done > "$out/truth_of_used.txt"
# One line per step: measured mean ± 95 % CI, against the nominal and the used frames' truth.
awk -F, -v nominal="${diams[*]}" '
  BEGIN { split(nominal, nom, " ") }
  FILENAME ~ /truth_of_used/ { split($0, a, " "); used[a[1]] = a[2]; next }
  /^#/ || $1 == "step" { next }
  {
    printf "  step %s  %6.1f °C   measured %8.2f ± %4.2f µm   nominal %6.1f (%+5.2f)   frames used %8.2f (%+5.2f)\n",
      $1, $2, $4, $7, nom[$1], $4 - nom[$1], used[$1], $4 - used[$1]
  }' "$out/truth_of_used.txt" "$out/results/diameters.csv"
echo
echo "Results: $out/results/ (summary.md, diameters.csv, frames.csv, overlays/, predict/)"
