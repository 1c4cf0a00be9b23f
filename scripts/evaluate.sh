#!/usr/bin/env bash
# The body of `make evaluate`: the thesis' studies on ../shared/data, opencv-doc's graf pair and
# rendered routes, written to output/evaluation/ (CSV and JSON per study), then
# output/evaluation/report.md with its plots (scripts/evaluation_report.py). About 10 minutes on
# two cores; each step says what it runs.
set -euo pipefail
cd "$(dirname "$0")/.."
DATA=${STEREO_FABMAP_SLAM_DATA:-../shared/data}
OUT=${EVALUATION_OUTPUT:-output/evaluation}
BIN=build/bin
START=$(date +%s)
step() { echo "[$(( $(date +%s) - START )) s] $*"; }

rm -rf "$OUT"
mkdir -p "$OUT/routes"
{
  echo "machine: $(lscpu | sed -n 's/^Model name: *//p'), $(nproc) cores, $(free -g | awk '/Mem:/{print $2}') GB"
  echo "date:    $(date -u +%Y-%m-%d)  commit: $(git rev-parse --short HEAD 2>/dev/null || echo unknown)"
} > "$OUT/machine.txt"

# Rendered routes (exact ground truth): 34 s of the loop is one lap and back past the start,
# 40 s of the figure eight crosses its centre four times.
step "rendering routes"
$BIN/make_synthetic_sequence --output "$OUT/routes/loop" --route loop --seconds 34 --seed 1 --no-bag > /dev/null
$BIN/make_synthetic_sequence --output "$OUT/routes/figure8" --route figure8 --seconds 40 --seed 2 --no-bag > /dev/null

step "descriptors: boat, graf, illumination, MH01_first10s, rendered loop"
$BIN/evaluate_descriptors --output "$OUT/descriptors" --oxford "$DATA/oxford/boat" \
  --graf /usr/share/doc/opencv-doc/examples/data --illumination "$DATA/oxford/boat/img1.pgm" \
  --euroc "$DATA/euroc/MH01_first10s,$OUT/routes/loop" > /dev/null

step "PnP kernels: MH01_first10s, V101_micro, rendered loop and figure eight"
$BIN/evaluate_pnp "$DATA/euroc/MH01_first10s" "$DATA/euroc/V101_micro" "$OUT/routes/loop" \
  "$OUT/routes/figure8" --output "$OUT/pnp" > /dev/null

# Which part of each sequence is mapped: the EuRoC subsets, the first half of their frames with
# ground truth (the tool's default; the camera goes on into views it has partly seen); the
# loop's first lap, the figure eight's first 20 s.
declare -A MAP=([MH01_first10s]="" [V101_micro]="" [loop]="--map-until 26" [figure8]="--map-until 20")
declare -A SEQUENCE=([MH01_first10s]="$DATA/euroc/MH01_first10s" [V101_micro]="$DATA/euroc/V101_micro"
                     [loop]="$OUT/routes/loop" [figure8]="$OUT/routes/figure8")
ORDER="MH01_first10s V101_micro loop figure8"

for name in $ORDER; do
  step "place recognition: $name"
  # V101_micro has 3.7 s of ground truth: a 1 s window leaves it queries (it hovers).
  window=$([ "$name" = V101_micro ] && echo 1 || echo 5)
  $BIN/evaluate_place_recognition "${SEQUENCE[$name]}" --exclude-seconds "$window" \
    --output "$OUT/place_recognition/$name" > /dev/null
done

for name in $ORDER; do
  step "relocalization: $name (${MAP[$name]:-default split})"
  $BIN/evaluate_relocalization "${SEQUENCE[$name]}" ${MAP[$name]} --quiet \
    --output "$OUT/relocalization/$name" > /dev/null
done

mkdir -p "$OUT/presets"
echo "sequence,preset,run_summary,relocalization_summary" > "$OUT/presets/presets.csv"
for name in $ORDER; do
  for preset in less more most; do
    step "keyframes_$preset: $name"
    folder="$OUT/presets/$name/$preset"
    $BIN/run_dataset "${SEQUENCE[$name]}" --config "config/keyframes_$preset.yaml" --quiet \
      --output "$folder/run" > /dev/null
    $BIN/evaluate_relocalization "${SEQUENCE[$name]}" --config "config/keyframes_$preset.yaml" \
      ${MAP[$name]} --quiet --output "$folder/relocalization" > /dev/null
    echo "$name,$preset,$folder/run/summary.json,$folder/relocalization/summary.json" >> "$OUT/presets/presets.csv"
  done
done

step "report"
/usr/bin/python3 scripts/evaluation_report.py "$OUT"
step "done: $OUT/report.md"
