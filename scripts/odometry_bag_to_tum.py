#!/usr/bin/env python3
"""Writes the nav_msgs/Odometry poses of a recorded bag as a TUM trajectory and prints the
message counts of every topic, e.g. for make demo: odometry_bag_to_tum.py IN.bag OUT.txt."""
import sys

import rosbag


def main(bag_path, tum_path, topic="/odometry"):
    counts = {}
    with rosbag.Bag(bag_path) as bag, open(tum_path, "w") as out:
        out.write("# timestamp tx ty tz qx qy qz qw\n")
        for name, message, _ in bag.read_messages():
            counts[name] = counts.get(name, 0) + 1
            if name != topic:
                continue
            p, q = message.pose.pose.position, message.pose.pose.orientation
            out.write(f"{message.header.stamp.to_sec():.9f} {p.x:.9f} {p.y:.9f} {p.z:.9f} "
                      f"{q.x:.9f} {q.y:.9f} {q.z:.9f} {q.w:.9f}\n")
    for name in sorted(counts):
        print(f"{name} {counts[name]}")
    return 0 if counts.get(topic) else 1


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:]))
