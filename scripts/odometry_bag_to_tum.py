#!/usr/bin/env python3
"""Writes the nav_msgs/Odometry poses of a recorded bag as a TUM trajectory, the last pose of
every keyframe (after the backend's updates) as a second one, and prints the message counts of
every topic. For make demo: odometry_bag_to_tum.py IN.bag TRAJECTORY.txt KEYFRAMES.txt"""
import sys

import rosbag


def tum_line(stamp, pose):
    p, q = pose.position, pose.orientation
    return (f"{stamp:.9f} {p.x:.9f} {p.y:.9f} {p.z:.9f} "
            f"{q.x:.9f} {q.y:.9f} {q.z:.9f} {q.w:.9f}\n")


def main(bag_path, tum_path, keyframes_path):
    counts, keyframes = {}, {}  # keyframes: id -> (stamp, latest pose)
    with rosbag.Bag(bag_path) as bag, open(tum_path, "w") as out:
        out.write("# timestamp tx ty tz qx qy qz qw\n")
        for name, message, _ in bag.read_messages():
            counts[name] = counts.get(name, 0) + 1
            if name == "/odometry":
                out.write(tum_line(message.header.stamp.to_sec(), message.pose.pose))
            elif name == "/keyframes":
                keyframes[message.id] = (message.header.stamp.to_sec(), message.pose)
            elif name == "/keyframe_updates":
                for kf_id, pose in zip(message.keyframe_ids, message.keyframe_poses):
                    if kf_id in keyframes:
                        keyframes[kf_id] = (keyframes[kf_id][0], pose)
    with open(keyframes_path, "w") as out:
        out.write("# timestamp tx ty tz qx qy qz qw\n")
        for stamp, pose in sorted(keyframes.values(), key=lambda entry: entry[0]):
            out.write(tum_line(stamp, pose))
    for name in sorted(counts):
        print(f"{name} {counts[name]}")
    return 0 if counts.get("/odometry") else 1


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:]))
