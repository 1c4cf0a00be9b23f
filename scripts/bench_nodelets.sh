#!/usr/bin/env bash
# CPU and memory of each nodelet while a bag plays, and the fastest playback that skips no
# stereo pair (figures for docs/benchmarks.md; part of `make bench`). Every nodelet runs
# standalone (its own process: euroc_bag.launch standalone:=true) so that /proc can tell them
# apart; in one manager the same work is shared by one process.
#   scripts/bench_nodelets.sh [ASL_DIR] [RATES...]      (default MH01_first10s; 1 2 3 5)
set -euo pipefail
cd "$(dirname "$0")/.."
export PATH=/usr/bin:$PATH
DATA=${STEREO_FABMAP_SLAM_DATA:-../shared/data}
SEQUENCE=${1:-$DATA/euroc/MH01_first10s}
shift || true
RATES=${*:-1 2 3 5}
OUT=output/bench/nodelets
mkdir -p "$OUT"
bag=$OUT/$(basename "$SEQUENCE").bag
[ -f "$bag" ] || build/bin/euroc_to_bag "$SEQUENCE" "$bag" > /dev/null

launch_pid=
private_master_pid=
cleanup() {
  [ -n "$launch_pid" ] && kill -INT "$launch_pid" 2> /dev/null || true
  [ -n "$private_master_pid" ] && kill "$private_master_pid" 2> /dev/null || true
  wait 2> /dev/null || true
}
trap cleanup EXIT
source scripts/private_master.sh
mkdir -p "$OUT/ros"
start_private_master "$PWD/$OUT/ros"
ticks=$(getconf CLK_TCK)
duration=$(rosbag info -y -k duration "$bag")
frames=$(grep -vc '^#' "$SEQUENCE/mav0/cam0/data.csv")
# Seconds of images (the bag may hold ground truth beyond them).
images=$(awk -F, '!/^#/ {if (!first) first = $1; last = $1} END {print (last - first) / 1e9 + 0.05}' \
  "$SEQUENCE/mav0/cam0/data.csv")

echo "machine: $(lscpu | sed -n 's/^Model name: *//p'), $(nproc) cores; bag $(basename "$bag"), $frames pairs over $images s"
echo
echo "| rate | pairs with odometry | pairs without (skip reports) | nodelet | CPU [s] | CPU [% of a core while images play] | peak RSS [MB] |"
echo "| --- | --- | --- | --- | --- | --- | --- |"
for rate in $RATES; do
  log=$OUT/rate_$rate.log
  PYTHONUNBUFFERED=1 rostopic echo -p /odometry/header/stamp > "$OUT/odometry_$rate.csv" 2> /dev/null &
  echo_pid=$!
  roslaunch stereo_fabmap_slam euroc_bag.launch bag:="$PWD/$bag" rate:="$rate" standalone:=true \
    visualizer:=false exit_at_end:=false delay:=4 > "$log" 2>&1 &
  launch_pid=$!
  until launched_node_running "$launch_pid" bag_player; do sleep 0.3; done
  while launched_node_running "$launch_pid" bag_player; do sleep 0.3; done
  sleep 3  # the Backend's and LoopDetector's last keyframes
  playing=$(/usr/bin/python3 -c "print($images / $rate)")
  odometry=$(grep -c '^[0-9]' "$OUT/odometry_$rate.csv" || true)
  for kind in StereoTracker Backend LoopDetector; do
    pid=$(pgrep -f "nodelet standalone stereo_fabmap_slam/$kind" | head -1)
    read -r utime stime <<< "$(awk '{print $14, $15}' /proc/"$pid"/stat)"
    rss=$(awk '/VmHWM/ {print $2}' /proc/"$pid"/status)
    seconds=$(/usr/bin/python3 -c "print(f'{($utime + $stime) / $ticks:.2f}')")
    cpu=$(/usr/bin/python3 -c "print(f'{100 * $seconds / $playing:.0f}')")
    reports=$(grep -c "skipped .* stereo pair" "$log" || true)
    echo "| $rate | $odometry of $frames | $((frames - odometry)) ($reports reports) | $kind | $seconds | $cpu | $((rss / 1024)) |"
  done
  kill -INT "$launch_pid"; wait "$launch_pid" 2> /dev/null || true; launch_pid=
  kill "$echo_pid" 2> /dev/null || true
done
echo
echo "CPU [s]: the process's user + system time from start (vocabulary and calibration loading"
echo "included) to 3 s after the bag; [%]: that over the seconds the images play at that rate."
echo "Peak RSS: VmHWM of the process."
