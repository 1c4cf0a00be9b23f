# Sourced by the scripts that run the ROS graph (demo, screenshots, benchmarks): a roscore of
# their own on a free port, so that they neither need nor disturb a ROS already running.
#   source scripts/private_master.sh; start_private_master LOG_DIR
# sets ROS_MASTER_URI and ROS_HOME (logs in LOG_DIR), starts roscore, waits until it answers
# and leaves its pid in private_master_pid for the caller's cleanup.
# Also defines launched_node_running LAUNCH_PID NAME (e.g. waiting for the bag player to end).
start_private_master() {
  local log_dir=$1 port
  set +u; source build/ws/devel/setup.bash; set -u  # setup files read unset variables
  port=$(/usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
  export ROS_MASTER_URI=http://127.0.0.1:$port ROS_HOME=$log_dir
  roscore -p "$port" > "$log_dir/roscore.log" 2>&1 &
  private_master_pid=$!
  until rosparam list > /dev/null 2>&1; do sleep 0.2; done
}

# Whether the node NAME of the roslaunch with pid LAUNCH_PID runs, asked of the process table
# (roslaunch starts its nodes as its children) rather than of the master: `rosnode list` can go
# unanswered for seconds while the disk writes out a bag rendered just before, and three misses
# in a row once ended the demo's wait for its bag 19 s into 40.
launched_node_running() {
  pgrep -P "$1" -f "__name:=$2( |\$)" > /dev/null
}
