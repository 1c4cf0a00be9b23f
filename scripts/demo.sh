#!/usr/bin/env bash
# The body of `make demo`, run after `make build`: the real ROS graph, headless, on the default
# sequence, then an evaluation against ground truth. Files go to output/demo/.
#
# The default sequence is rendered by the project itself (make_synthetic_sequence: the textured
# hall, route "loop", 40 s, seed 1) on the first run and cached; nothing is downloaded.
# DEMO_SEQUENCE=<EuRoC ASL folder> plays a real sequence instead; DEMO_RATE sets the playback
# speed (default 1); RVIZ=1 opens rviz.
set -euo pipefail
cd "$(dirname "$0")/.."
export PATH=/usr/bin:$PATH
BIN=build/bin
OUT=output/demo
RATE=${DEMO_RATE:-1}
mkdir -p "$OUT"
rm -f "$OUT/relocalize.txt" "$OUT/relocalization.txt"
SECONDS=0
if [ -n "${DEMO_SEQUENCE:-}" ]; then
  SEQUENCE=$DEMO_SEQUENCE
  NAME=$(basename "$SEQUENCE")
  [ -d "$SEQUENCE/mav0" ] || { echo "demo: no EuRoC sequence at $SEQUENCE" >&2; exit 1; }
  bag="$OUT/$NAME.bag"
  if [ ! -f "$bag" ] || [ -n "$(find "$SEQUENCE/mav0" -newer "$bag" -print -quit)" ]; then
    echo "== converting $SEQUENCE to $bag"
    "$BIN/euroc_to_bag" "$SEQUENCE" "$bag"
  fi
else
  NAME=synthetic_loop
  SEQUENCE=$OUT/$NAME
  bag=$SEQUENCE/sequence.bag
  if [ ! -f "$bag" ] || [ "$BIN/make_synthetic_sequence" -nt "$bag" ]; then
    echo "== rendering the synthetic hall (route loop, 40 s; cached for later runs)"
    rm -rf "$SEQUENCE"
    render_start=$SECONDS
    "$BIN/make_synthetic_sequence" --output "$SEQUENCE" --route loop --seconds 40 --seed 1 > /dev/null
    echo "   rendered 800 stereo frames in $((SECONDS - render_start)) s"
  fi
fi
echo "== using $bag"
# A rendered sequence brings its rig's calibration; EuRoC sequences share config/euroc_stereo.yaml.
calibration=$PWD/config/euroc_stereo.yaml
[ -f "$SEQUENCE/stereo_calibration.yaml" ] && calibration=$PWD/$SEQUENCE/stereo_calibration.yaml

# A private master on a free port, so that the demo neither needs nor disturbs a running ROS.
cleanup() {
  kill "$recorder_pid" 2> /dev/null || true; kill -INT "$launch_pid" 2> /dev/null || true
  kill "$private_master_pid" 2> /dev/null || true; wait 2> /dev/null || true
}
recorder_pid=
launch_pid=
private_master_pid=
trap cleanup EXIT
source scripts/private_master.sh
mkdir -p "$OUT/ros"
start_private_master "$PWD/$OUT/ros"

echo "== running the ROS graph: nodelet manager + StereoTracker + Backend + LoopDetector + Visualizer, rosbag play $bag"
rosbag record -q -O "$OUT/recorded.bag" /odometry /keyframes /keyframe_updates /loop_edges /map_graph \
  > /dev/null 2>&1 &
recorder_pid=$!
sleep 1
graph_start=$SECONDS
rviz=false
[ "${RVIZ:-0}" = 1 ] && rviz=true
# The graph stays up after the bag (exit_at_end:=false) for the relocalize call below.
roslaunch stereo_fabmap_slam euroc_bag.launch bag:="$PWD/$bag" rate:="$RATE" calibration:="$calibration" \
  exit_at_end:=false rviz:=$rviz > "$OUT/roslaunch.log" 2>&1 &
launch_pid=$!
duration=$(rosbag info -y -k duration "$bag" | cut -d. -f1)
deadline=$((SECONDS + 60 + 3 * duration))
until launched_node_running "$launch_pid" bag_player; do
  kill -0 "$launch_pid" 2> /dev/null && [ $SECONDS -lt $deadline ] || {
    echo "demo: the ROS graph failed; see $OUT/roslaunch.log" >&2; exit 1; }
  sleep 0.5
done
while launched_node_running "$launch_pid" bag_player; do
  kill -0 "$launch_pid" 2> /dev/null && [ $SECONDS -lt $deadline ] || {
    echo "demo: the ROS graph failed; see $OUT/roslaunch.log" >&2; exit 1; }
  sleep 0.5
done
graph_seconds=$((SECONDS - graph_start))
sleep 1
kill -INT "$recorder_pid"; wait "$recorder_pid" 2> /dev/null || true
recorder_pid=

# Relocalization through the graph: the bag's first 4 s again (the tracker sees time go back
# and starts afresh) while the relocalize service finds the camera in the map.
echo "== relocalize: replaying the first 4 s and calling the relocalize service"
(sleep 2; rosservice call /relocalize "{timeout: 3.0, reanchor: false}" > "$OUT/relocalize.txt" 2>&1) &
caller_pid=$!
rosbag play --clock --quiet -u 4 "$bag" > /dev/null 2>&1
wait "$caller_pid" || true
kill -INT "$launch_pid" 2> /dev/null || true
wait "$launch_pid" 2> /dev/null || true

echo "== evaluating against ground truth"
/usr/bin/python3 scripts/odometry_bag_to_tum.py "$OUT/recorded.bag" "$OUT/odometry.txt" \
  "$OUT/keyframes.txt" "$OUT/trajectory.txt" "$OUT/loops.txt" "$OUT/relocalizations.txt" \
  > "$OUT/topics.txt"
# The odometry is the base's (REP-105 base_link): the ground truth moves to it.
gt=(--gt "$SEQUENCE/mav0/state_groundtruth_estimate0/data.csv" --gt-to-base "$calibration")
"$BIN/evaluate_trajectory" "${gt[@]}" --est "$OUT/odometry.txt" > "$OUT/evaluation_odometry.txt"
"$BIN/evaluate_trajectory" "${gt[@]}" --est "$OUT/trajectory.txt" --keyframes "$OUT/keyframes.txt" \
  --loops "$OUT/loops.txt" --relocalizations "$OUT/relocalizations.txt" --plot "$OUT/trajectory.png" \
  > "$OUT/evaluation.txt"
loops_present="unknown (real data)"
if [ -f "$SEQUENCE/mav0/synthetic.yaml" ]; then
  loops_present=$(sed -n 's/^revisits: \[\(.*\)\]/\1/p' "$SEQUENCE/mav0/synthetic.yaml" | awk -F, 'NF == 0 {print 0} NF > 0 {print NF}')
fi
frames=$(grep -c . "$SEQUENCE/mav0/cam0/data.csv"); frames=$((frames - 1))
count() { awk -v topic="$1" '$1 == topic {print $2}' "$OUT/topics.txt"; }
odometry=$(count /odometry)
keyframes=$(count /keyframes)
loop_edges=$(count /loop_edges)
first_loop=$(awk '!/^#/ {print $1; exit}' "$OUT/loops.txt")
start=$(awk '!/^#/ {print $1; exit}' "$OUT/odometry.txt")
ate=$(awk '/^ATE/ {print $3}' "$OUT/evaluation.txt")
ate_odometry=$(awk '/^ATE/ {print $3}' "$OUT/evaluation_odometry.txt")
# The relocalized pose in TUM, measured with the map trajectory's alignment to ground truth.
relocalization=$(/usr/bin/python3 - "$OUT/relocalize.txt" "$OUT/relocalization.txt" <<'PYTHON'
import sys, yaml
try:
    answer = yaml.safe_load(open(sys.argv[1]))
except Exception:
    answer = None
if not isinstance(answer, dict):
    print("failed: " + open(sys.argv[1]).read().strip().replace("\n", " ")[:120])
    sys.exit()
if not answer["success"]:
    print("failed: " + answer["message"])
    sys.exit()
pose = answer["pose"]
stamp = pose["header"]["stamp"]["secs"] + 1e-9 * pose["header"]["stamp"]["nsecs"]
p, q = pose["pose"]["position"], pose["pose"]["orientation"]
with open(sys.argv[2], "w") as out:
    out.write(f"{stamp:.9f} {p['x']} {p['y']} {p['z']} {q['x']} {q['y']} {q['z']} {q['w']}\n")
print(f"found against keyframe {answer['keyframe_id']} ({answer['inliers']} inliers, "
      f"{answer['time_ms']:.1f} ms)")
PYTHON
)
if [ -f "$OUT/relocalization.txt" ] && [ "${relocalization#found}" != "$relocalization" ]; then
  error=$("$BIN/evaluate_trajectory" "${gt[@]}" --est "$OUT/trajectory.txt" --poses "$OUT/relocalization.txt" \
    | awk '/^pose/ {printf "%.2f cm, %.2f deg", 100 * $3, $5}')
  relocalization="$relocalization, error ${error} against ground truth"
fi
echo
echo "demo summary ($NAME)"
echo "  frames played           $frames"
echo "  odometry messages       $odometry"
echo "  keyframes               ${keyframes:-0}"
echo "  loop edges accepted     ${loop_edges:-0}${first_loop:+ (first at $(awk -v a="$first_loop" -v b="$start" 'BEGIN {printf "%.1f", a - b}') s)}"
echo "  revisits present        $loops_present"
echo "  ATE RMSE odometry       $ate_odometry cm"
echo "  ATE RMSE loop-closed    $ate cm"
echo "  relocalization          $relocalization"
echo "  ROS graph run time      ${graph_seconds} s (bag of $(rosbag info -y -k duration "$bag" | cut -c1-5) s at rate $RATE)"
echo "  files                   $OUT/trajectory.txt, odometry.txt, keyframes.txt, loops.txt, trajectory.png, evaluation.txt, relocalize.txt"
echo "== demo done in ${SECONDS} s"
