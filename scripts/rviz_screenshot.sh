#!/usr/bin/env bash
# Plays a bag through launch/euroc_bag.launch with rviz:=true (config/stereo_fabmap_slam.rviz)
# under a virtual X server, and saves a screenshot of rviz once the bag has ended: what a user
# sees before installing (docs/ and the README show these).
#   scripts/rviz_screenshot.sh BAG OUT.png [CALIBRATION.yaml] [roslaunch arg:=value ...]
# RVIZ_VIEW="DISTANCE X Y [FRAME]" moves the shipped config's orbit view (distance [m], focal
# point [m] in FRAME, by default the shipped one, base_link: the view follows the camera), e.g.
# "19 2 3 map" for an overview of a whole route; everything else stays as shipped.
# RVIZ_WAIT=S waits S seconds after the bag's end (default 4): with dense:=true the DenseMapper,
# below the tracker's priority and beside rviz's software rendering, is still fusing then.
# Needs `make build` and the packages rviz, xvfb and imagemagick (`make screenshots` installs
# them and makes the pictures in docs/).
set -euo pipefail
cd "$(dirname "$0")/.."
export PATH=/usr/bin:$PATH
if [ $# -lt 2 ]; then
  echo "usage: $0 BAG OUT.png [CALIBRATION.yaml] [roslaunch arg:=value ...]" >&2
  exit 2
fi
if [ -z "${RVIZ_SCREENSHOT_IN_XVFB:-}" ]; then
  for tool in rviz xvfb-run import; do
    command -v "$tool" > /dev/null || {
      echo "$0: '$tool' is missing: apt-get install rviz xvfb imagemagick (or make screenshots)" >&2
      exit 1
    }
  done
  RVIZ_SCREENSHOT_IN_XVFB=1 exec xvfb-run -a -s "-screen 0 1440x900x24" "$0" "$@"
fi
bag=$(realpath "$1")
out=$2
calibration=$(realpath "${3:-config/euroc_stereo.yaml}")
shift 2
[ $# -gt 0 ] && shift
[ -f "$bag" ] || { echo "$0: no bag at $bag" >&2; exit 1; }
log_dir=$(mktemp -d)

launch_pid=
private_master_pid=
cleanup() {
  [ -n "$launch_pid" ] && kill -INT "$launch_pid" 2> /dev/null || true
  [ -n "$private_master_pid" ] && kill "$private_master_pid" 2> /dev/null || true
  wait 2> /dev/null || true
}
trap cleanup EXIT
source scripts/private_master.sh
start_private_master "$log_dir"

config=$PWD/config/stereo_fabmap_slam.rviz
if [ -n "${RVIZ_VIEW:-}" ]; then
  read -r distance focal_x focal_y frame <<< "$RVIZ_VIEW"
  /usr/bin/python3 - "$config" "$log_dir/view.rviz" "$distance" "$focal_x" "$focal_y" \
    "${frame:-}" <<'PYTHON'
import re, sys
text = open(sys.argv[1]).read()
text = re.sub(r"(\n      Distance: )[0-9.]+", r"\g<1>" + sys.argv[3], text)
text = re.sub(r"(Focal Point:\n        X: )[-0-9.]+(\n        Y: )[-0-9.]+",
              r"\g<1>" + sys.argv[4] + r"\g<2>" + sys.argv[5], text)
if sys.argv[6]:
    text = re.sub(r"(\n      Target Frame: )\S+", r"\g<1>" + sys.argv[6], text)
open(sys.argv[2], "w").write(text)
PYTHON
  config=$log_dir/view.rviz
fi
roslaunch stereo_fabmap_slam euroc_bag.launch bag:="$bag" calibration:="$calibration" rviz:=true \
  rviz_config:="$config" delay:=6 "$@" > "$log_dir/roslaunch.log" 2>&1 &
launch_pid=$!
duration=$(rosbag info -y -k duration "$bag" | cut -d. -f1)
deadline=$((SECONDS + 90 + 3 * duration + ${RVIZ_WAIT:-4}))
echo "playing $bag ($duration s) with rviz; logs in $log_dir"
until launched_node_running "$launch_pid" bag_player; do
  [ $SECONDS -lt $deadline ] && kill -0 "$launch_pid" 2> /dev/null || {
    echo "$0: the ROS graph failed; see $log_dir/roslaunch.log" >&2; exit 1; }
  sleep 0.5
done
while launched_node_running "$launch_pid" bag_player; do
  [ $SECONDS -lt $deadline ] || { echo "$0: the bag did not end in time" >&2; exit 1; }
  sleep 0.5
done
sleep "${RVIZ_WAIT:-4}"  # the Visualizer's (and DenseMapper's) last refresh and rviz's next frames
# rviz under Xvfb's software OpenGL now and then aborts at start: a black picture is no picture.
if ! launched_node_running "$launch_pid" rviz; then
  echo "$0: rviz is not running (see $log_dir/log); try again" >&2
  exit 3
fi
import -window root "$out"
echo "saved $out"
