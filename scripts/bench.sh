#!/usr/bin/env bash
# The body of `make bench`: runs the offline odometry on the EuRoC subsets a few times and
# prints the figures docs/benchmarks.md records (accuracy is deterministic; times vary a little
# from run to run, so each time is the median over the runs).
set -euo pipefail
cd "$(dirname "$0")/.."
DATA=${STEREO_FABMAP_SLAM_DATA:-../shared/data}
RUNS=${BENCH_RUNS:-3}
OUT=output/bench
mkdir -p "$OUT"

echo "machine: $(lscpu | sed -n 's/^Model name: *//p'), $(nproc) cores, $(free -g | awk '/Mem:/{print $2}') GB"
echo "date:    $(date -u +%Y-%m-%d)  commit: $(git rev-parse --short HEAD 2>/dev/null || echo unknown)"
echo
for sequence in MH01_first10s V101_micro; do
  for run in $(seq 1 "$RUNS"); do
    build/bin/run_dataset "$DATA/euroc/$sequence" --quiet --output "$OUT/$sequence/run$run" > /dev/null
  done
done
/usr/bin/python3 - "$OUT" "$RUNS" <<'PYTHON'
import json, statistics, sys
out, runs = sys.argv[1], int(sys.argv[2])
rows = [
    ("frames tracked", lambda s: f"{s[0]['frames_tracked']}/{s[0]['frames']}"),
    ("keyframes", lambda s: f"{s[0]['keyframes']}"),
    ("ATE RMSE (SE3) [cm]", lambda s: f"{100 * s[0]['ate_rmse']:.3f}"),
    ("ATE max [cm]", lambda s: f"{100 * s[0]['ate_max']:.3f}"),
    ("displacement error [cm]", lambda s: f"{100 * s[0]['displacement_error']:.3f}"),
    ("tracking median [ms]", lambda s: f"{statistics.median(r['tracking_total_ms_median'] for r in s):.2f}"),
    ("  detection [ms]", lambda s: f"{statistics.median(r['detection_ms_median'] for r in s):.2f}"),
    ("  description [ms]", lambda s: f"{statistics.median(r['description_ms_median'] for r in s):.2f}"),
    ("  stereo [ms]", lambda s: f"{statistics.median(r['stereo_ms_median'] for r in s):.2f}"),
    ("  tracking [ms]", lambda s: f"{statistics.median(r['tracking_ms_median'] for r in s):.2f}"),
    ("rectification median [ms]", lambda s: f"{statistics.median(r['rectification_ms_median'] for r in s):.2f}"),
    ("bundle adjustment mean/frame [ms]", lambda s: f"{statistics.median(r['bundle_adjustment_ms_mean'] for r in s):.2f}"),
    ("pipeline x real time", lambda s: f"{statistics.median(r['realtime_factor'] for r in s):.2f}"),
    ("cores used (cpu/wall)", lambda s: f"{statistics.median(r['cpu_time_s'] / r['wall_time_s'] for r in s):.2f}"),
    ("peak RSS [MB]", lambda s: f"{max(r['peak_rss_mb'] for r in s):.0f}"),
]
sequences = ["MH01_first10s", "V101_micro"]
summaries = {q: [json.load(open(f"{out}/{q}/run{i}/summary.json")) for i in range(1, runs + 1)] for q in sequences}
print(f"| run_dataset, {runs} runs each | " + " | ".join(sequences) + " |")
print("| --- | " + " | ".join("---" for _ in sequences) + " |")
for name, cell in rows:
    print(f"| {name} | " + " | ".join(cell(summaries[q]) for q in sequences) + " |")
PYTHON

echo
echo "dense map (run_dataset --dense, issue 33's budget: depth + fusion <= 40 ms a keyframe):"
echo
for run in $(seq 1 "$RUNS"); do
  build/bin/run_dataset "$DATA/euroc/MH01_first10s" --quiet --dense --output "$OUT/dense/run$run" > /dev/null
done
/usr/bin/python3 - "$OUT/dense" "$RUNS" <<'PYTHON'
import json, statistics, sys
out, runs = sys.argv[1], int(sys.argv[2])
s = [json.load(open(f"{out}/run{i}/summary.json")) for i in range(1, runs + 1)]
median = lambda key: statistics.median(r[key] for r in s)
print(f"| MH01_first10s --dense, {runs} runs | median |")
print("| --- | --- |")
print(f"| keyframes fused | {s[0]['dense_keyframes']} |")
print(f"| depth a keyframe [ms] | {median('dense_depth_ms_median'):.1f} |")
print(f"| fusion a keyframe [ms] | {median('dense_fusion_ms_median'):.1f} |")
print(f"| depth + fusion [ms] | {statistics.median(r['dense_depth_ms_median'] + r['dense_fusion_ms_median'] for r in s):.1f} |")
print(f"| blocks, volume [MB] | {s[0]['dense_blocks']}, {s[0]['dense_volume_mb']:.0f} |")
print(f"| mesh vertices | {s[0]['dense_mesh_vertices']} |")
PYTHON

echo
echo "place recognition (build/bin/benchmark_fabmap: synthetic words, fixed seeds, one core):"
echo
build/bin/benchmark_fabmap

echo
echo "the ROS graph, per nodelet (scripts/bench_nodelets.sh):"
echo
bash scripts/bench_nodelets.sh
