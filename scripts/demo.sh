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
rm -f "$OUT/relocalize.txt" "$OUT/relocalization.txt" "$OUT/mesh.ply" "$OUT/dense_map.png"
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
  kill -INT "$launch_pid" 2> /dev/null || true
  kill "$private_master_pid" 2> /dev/null || true; wait 2> /dev/null || true
}
launch_pid=
private_master_pid=
trap cleanup EXIT
source scripts/private_master.sh
mkdir -p "$OUT/ros"
start_private_master "$PWD/$OUT/ros"

# The graph writes its run as run_dataset does (output:=, the Recorder nodelet) and its map
# (save_map:=) when it shuts down at the end of the bag.
RUN=$OUT/run
rm -rf "$RUN"
echo "== running the ROS graph: nodelet manager + StereoTracker + Backend + LoopDetector + Visualizer + DenseMapper + Recorder, rosbag play $bag"
graph_start=$SECONDS
rviz=false
[ "${RVIZ:-0}" = 1 ] && rviz=true
duration=$(rosbag info -y -k duration "$bag" | cut -d. -f1)
timeout $((60 + 3 * duration)) roslaunch stereo_fabmap_slam euroc_bag.launch bag:="$PWD/$bag" \
  rate:="$RATE" calibration:="$calibration" exit_at_end:=true rviz:=$rviz output:="$PWD/$RUN" \
  save_map:="$PWD/$OUT/map.bin" dense:=true save_mesh:="$PWD/$OUT/mesh.ply" \
  > "$OUT/roslaunch.log" 2>&1 || {
  echo "demo: the ROS graph failed; see $OUT/roslaunch.log" >&2; exit 1; }
graph_seconds=$((SECONDS - graph_start))
[ -f "$RUN/summary.json" ] || { echo "demo: no run written; see $OUT/roslaunch.log" >&2; exit 1; }

# Relocalization through the graph: a new graph loads the saved map, the bag's first 4 s are
# played into it, and the relocalize service finds the camera in the map.
echo "== relocalize: loading the map into a new graph, playing the first 4 s, calling relocalize"
rosparam set use_sim_time true
roslaunch stereo_fabmap_slam euroc.launch calibration:="$calibration" visualizer:=false \
  map_file:="$PWD/$OUT/map.bin" > "$OUT/roslaunch_relocalize.log" 2>&1 &
launch_pid=$!
until rosservice list 2> /dev/null | grep -q '^/relocalize$'; do
  kill -0 "$launch_pid" 2> /dev/null || { echo "demo: see $OUT/roslaunch_relocalize.log" >&2; exit 1; }
  sleep 0.5
done
(sleep 2; rosservice call /relocalize "{timeout: 3.0, reanchor: false}" > "$OUT/relocalize.txt" 2>&1) &
caller_pid=$!
timeout 20 rostopic echo -n 1 /tf_static > "$OUT/tf_static.txt" 2>&1 &
mount_pid=$!
rosbag play --clock --quiet -u 4 "$bag" > /dev/null 2>&1
wait "$caller_pid" || true
wait "$mount_pid" || true
kill -INT "$launch_pid" 2> /dev/null || true
wait "$launch_pid" 2> /dev/null || true
launch_pid=

echo "== evaluating against ground truth"
# The run's files are the rectified left camera's, as run_dataset's: the ground truth moves to it.
gt=(--gt "$SEQUENCE/mav0/state_groundtruth_estimate0/data.csv" --gt-to-rectified "$calibration")
awk -F, 'NR > 1 && $7 == 1 {print $2, $4}' "$RUN/loops.csv" > "$OUT/loops.txt"
"$BIN/evaluate_trajectory" "${gt[@]}" --est "$RUN/odometry.txt" > "$OUT/evaluation_odometry.txt"
"$BIN/evaluate_trajectory" "${gt[@]}" --est "$RUN/trajectory.txt" --keyframes "$RUN/keyframes.txt" \
  --loops "$OUT/loops.txt" --plot "$OUT/trajectory.png" > "$OUT/evaluation.txt"
loops_present="unknown (real data)"
if [ -f "$SEQUENCE/mav0/synthetic.yaml" ]; then
  loops_present=$(sed -n 's/^revisits: \[\(.*\)\]/\1/p' "$SEQUENCE/mav0/synthetic.yaml" | awk -F, 'NF == 0 {print 0} NF > 0 {print NF}')
fi
frames=$(grep -c . "$SEQUENCE/mav0/cam0/data.csv"); frames=$((frames - 1))
number() { /usr/bin/python3 -c "import json, sys; print(json.load(open(sys.argv[1]))[sys.argv[2]])" "$RUN/summary.json" "$1"; }
tracked=$(number frames_tracked)
keyframes=$(number keyframes)
loops_accepted=$(number loops_accepted)
first_loop=$(awk '{print $1; exit}' "$OUT/loops.txt")
start=$(awk '!/^#/ {print $1; exit}' "$RUN/odometry.txt")
ate=$(awk '/^ATE/ {print $3}' "$OUT/evaluation.txt")
ate_odometry=$(awk '/^ATE/ {print $3}' "$OUT/evaluation_odometry.txt")
# The relocalized pose in TUM, measured with the map trajectory's alignment to ground truth.
relocalization=$(/usr/bin/python3 - "$OUT/relocalize.txt" "$OUT/relocalization.txt" "$OUT/tf_static.txt" <<'PYTHON'
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
# The service answers the base's pose; the run's trajectory is the camera's: base * mounting.
mount = yaml.safe_load(open(sys.argv[3]).read().split("---")[0])["transforms"][0]["transform"]
def mul(a, b):
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (aw * bx + ax * bw + ay * bz - az * by, aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw, aw * bw - ax * bx - ay * by - az * bz)
def rotate(q, v):
    x, y, z, _ = mul(mul(q, (v[0], v[1], v[2], 0.0)), (-q[0], -q[1], -q[2], q[3]))
    return (x, y, z)
p, q = pose["pose"]["position"], pose["pose"]["orientation"]
qb = (q["x"], q["y"], q["z"], q["w"])
t, r = mount["translation"], mount["rotation"]
qm = (r["x"], r["y"], r["z"], r["w"])
offset = rotate(qb, (t["x"], t["y"], t["z"]))
position = (p["x"] + offset[0], p["y"] + offset[1], p["z"] + offset[2])
qc = mul(qb, qm)
with open(sys.argv[2], "w") as out:
    out.write(f"{stamp:.9f} {position[0]} {position[1]} {position[2]} {qc[0]} {qc[1]} {qc[2]} {qc[3]}\n")
print(f"found against keyframe {answer['keyframe_id']} ({answer['inliers']} inliers, "
      f"{answer['time_ms']:.1f} ms)")
PYTHON
)
if [ -f "$OUT/relocalization.txt" ] && [ "${relocalization#found}" != "$relocalization" ]; then
  error=$("$BIN/evaluate_trajectory" "${gt[@]}" --est "$RUN/trajectory.txt" --poses "$OUT/relocalization.txt" \
    | awk '/^pose/ {printf "%.2f cm, %.2f deg", 100 * $3, $5}')
  relocalization="$relocalization, error ${error} against ground truth"
fi
# The dense map the DenseMapper wrote at shutdown: against the rendered hall's exact geometry
# (a picture coloured by error, with the keyframes), or for a real sequence its size alone.
dense="no mesh written; see $OUT/roslaunch.log"
if [ -f "$OUT/mesh.ply" ] && [ -f "$SEQUENCE/mav0/synthetic.yaml" ]; then
  dense=$("$BIN/evaluate_reconstruction" "$OUT/mesh.ply" --sequence "$SEQUENCE" --run "$RUN" \
    --picture "$OUT/dense_map.png" 2> /dev/null | awk '
      /^points/ {n = $2} /^accuracy median/ {m = $3} /^accuracy 90/ {p = $4} /^completeness/ {c = $2}
      END {printf "%d vertices, %.1f / %.1f cm from the hall (median / 90 %%), %.0f %% of what the keyframes saw within 5 cm", n, 100 * m, 100 * p, 100 * c}')
elif [ -f "$OUT/mesh.ply" ]; then
  dense="$OUT/mesh.ply ($(du -h "$OUT/mesh.ply" | cut -f1))"
fi
echo
echo "demo summary ($NAME)"
echo "  frames played           $frames"
echo "  frames tracked          $tracked"
echo "  keyframes               ${keyframes:-0}"
echo "  loops accepted          ${loops_accepted:-0}${first_loop:+ (first at $(awk -v a="$first_loop" -v b="$start" 'BEGIN {printf "%.1f", a - b}') s)}"
echo "  revisits present        $loops_present"
echo "  ATE RMSE odometry       $ate_odometry cm"
echo "  ATE RMSE loop-closed    $ate cm"
echo "  relocalization          $relocalization"
echo "  dense map               $dense"
echo "  ROS graph run time      ${graph_seconds} s (bag of $(rosbag info -y -k duration "$bag" | cut -c1-5) s at rate $RATE)"
echo "  files                   $RUN/ (trajectory.txt, odometry.txt, keyframes.txt, loops.csv, timing.csv, summary.json), $OUT/map.bin, trajectory.png, evaluation.txt, relocalize.txt, mesh.ply, dense_map.png"
echo "== demo done in ${SECONDS} s"
