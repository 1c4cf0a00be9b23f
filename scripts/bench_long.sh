#!/usr/bin/env bash
# The body of `make bench-long` (not part of `make test`): 10 minutes of the rendered hall
# (route loop, 12,000 stereo frames, about 23 laps) through run_dataset with loop closing.
# Prints how memory grows with the keyframes (bytes per keyframe, a least-squares line through
# the resident memory every 100 frames), whether per-frame tracking time grows with the map
# (first against last minute), and FAB-MAP and pose-graph times at the end.
# About 20 minutes on 2 cores: rendering ~11, the run ~9 (13 on a slower machine of this kind).
set -euo pipefail
cd "$(dirname "$0")/.."
export PATH=/usr/bin:$PATH
SECONDS_OF_ROUTE=${BENCH_LONG_SECONDS:-600}
OUT=output/bench/long
mkdir -p "$OUT"
if [ ! -f "$OUT/sequence/mav0/cam0/data.csv" ]; then
  echo "rendering $SECONDS_OF_ROUTE s of the hall (route loop, seed 3)"
  rm -rf "$OUT/sequence"
  build/bin/make_synthetic_sequence --output "$OUT/sequence" --route loop \
    --seconds "$SECONDS_OF_ROUTE" --seed 3 --no-bag > /dev/null
fi
echo "running run_dataset (loop closing on)"
/usr/bin/time -v build/bin/run_dataset "$OUT/sequence" --output "$OUT/run" \
  > "$OUT/progress.txt" 2> "$OUT/time.txt"
/usr/bin/python3 - "$OUT" <<'PYTHON'
import csv, json, re, statistics, sys
out = sys.argv[1]
points = []  # (keyframes, resident MB)
for line in open(f"{out}/progress.txt"):
    m = re.match(r"frame (\d+)/\d+: \w+, (\d+) keyframes, resident ([\d.]+) MB", line)
    if m:
        points.append((int(m.group(2)), float(m.group(3))))
# Least squares past the first minute (start-up allocations, vocabulary, first keyframes).
fit = points[len(points) // 10:]
n = len(fit)
mx = sum(k for k, _ in fit) / n
my = sum(r for _, r in fit) / n
slope = sum((k - mx) * (r - my) for k, r in fit) / sum((k - mx) ** 2 for k, _ in fit)
rows = list(csv.DictReader(open(f"{out}/run/timing.csv")))
def median(values):
    values = [v for v in values if v == v]
    return statistics.median(values) if values else float("nan")
def column(name, part):
    return [float(r[name]) for r in part if r[name] not in ("", "nan")]
minute = 1200  # frames at 20 Hz
first, last = rows[:minute], rows[-minute:]
track = lambda part: median([float(r["detection_ms"]) + float(r["description_ms"]) +
                             float(r["stereo_ms"]) + float(r["tracking_ms"]) for r in part])
loops_last = [v for v in column("loop_detection_ms", last) if v > 0]
graph_last = [v for v in column("pose_graph_ms", last) if v > 0]
summary = json.load(open(f"{out}/run/summary.json"))
print(f"| measure | figure |")
print(f"| --- | --- |")
print(f"| frames, keyframes | {summary['frames']}, {summary['keyframes']} |")
print(f"| ATE RMSE loop-closed [cm] | {100 * summary.get('ate_rmse', float('nan')):.2f} |")
print(f"| resident memory at 1 min / end [MB] | {points[len(points) // 10][1]:.0f} / {points[-1][1]:.0f} |")
print(f"| memory per keyframe (fit past the first minute) | {slope * 1048576 / 1024:.0f} kB |")
print(f"| per-frame total (detection to tracking) median, first / last minute [ms] | {track(first):.2f} / {track(last):.2f} |")
# The stages of that time, and the tracked points: whether a growth is the map's (tracking,
# inliers) or the images' (detection, description, stereo).
for stage in ("detection", "description", "stereo", "tracking"):
    print(f"| {stage} median, first / last minute [ms] | "
          f"{median(column(stage + '_ms', first)):.2f} / {median(column(stage + '_ms', last)):.2f} |")
print(f"| inliers median, first / last minute | "
      f"{median(column('inliers', first)):.0f} / {median(column('inliers', last)):.0f} |")
print(f"| loop detection median, last minute [ms] | {median(loops_last):.2f} |")
print(f"| pose graph median / max, last minute [ms] | {median(graph_last):.1f} / {max(graph_last) if graph_last else float('nan'):.1f} |")
print(f"| peak RSS [MB] | {summary['peak_rss_mb']:.0f} |")
# Minute by minute: a time that grows with the map grows in every row, as the keyframes do; a
# first minute apart from the rest is the map filling its window (local map, bundle adjustment).
print()
print("| minute | keyframes at its end | detection | description | stereo | tracking | per-frame total | loop detection [ms, medians] |")
print("| --- | --- | --- | --- | --- | --- | --- | --- |")
keyframes = 0
for start in range(0, len(rows), minute):
    part = rows[start:start + minute]
    keyframes += sum(1 for r in part if r["keyframe"] not in ("", "0"))
    stages = " | ".join(f"{median(column(stage + '_ms', part)):.2f}"
                        for stage in ("detection", "description", "stereo", "tracking"))
    loops = [v for v in column("loop_detection_ms", part) if v > 0]
    print(f"| {start // minute + 1} | {keyframes} | {stages} | {track(part):.2f} | {median(loops):.2f} |")
PYTHON
