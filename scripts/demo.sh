#!/usr/bin/env bash
# The body of `make demo`, run after `make build`. It shows what the package can do so far on
# the default sequence and leaves its files in output/demo/.
#
# Today (foundation): the EuRoC subset from the shared data folder is converted to a rosbag that
# the ROS graph will play, and its contents are listed. The synthetic-world issue replaces the
# input with a rendered sequence and adds the ROS run and its evaluation.
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=build/bin
OUT=output/demo
DATA=${STEREO_FABMAP_SLAM_DATA:-../shared/data}
SEQUENCE=${DEMO_SEQUENCE:-$DATA/euroc/MH01_first10s}
mkdir -p "$OUT"

if [ ! -d "$SEQUENCE/mav0" ]; then
  echo "demo: no EuRoC sequence at $SEQUENCE (set DEMO_SEQUENCE=<ASL folder>)" >&2
  exit 1
fi

SECONDS=0
bag="$OUT/$(basename "$SEQUENCE").bag"
if [ ! -f "$bag" ] || [ -n "$(find "$SEQUENCE/mav0" -newer "$bag" -print -quit)" ]; then
  echo "== Converting $SEQUENCE to $bag"
  "$BIN/euroc_to_bag" "$SEQUENCE" "$bag"
else
  echo "== Using cached $bag"
fi
echo "== rosbag info $bag"
rosbag info "$bag"
echo "== demo done in ${SECONDS} s; files in $OUT/"
