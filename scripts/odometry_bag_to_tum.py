#!/usr/bin/env python3
"""Writes the trajectories of a recorded bag as TUM files and prints the message counts of every
topic. For make demo:

  odometry_bag_to_tum.py IN.bag ODOMETRY.txt KEYFRAMES.txt [MAP.txt LOOPS.txt [RELOCALIZATIONS.txt]]

ODOMETRY.txt: the nav_msgs/Odometry poses (odom frame). KEYFRAMES.txt: the last pose of every
keyframe, in the map frame of the last /map_graph when there is one (else odom, after the
backend's updates). MAP.txt: every odometry pose moved into the map frame by its keyframe's
final correction, T_map_kf * T_odom_kf^-1 * T_odom_camera (the trajectory after loop closing).
LOOPS.txt: one line "query_time match_time" per /loop_edges message. RELOCALIZATIONS.txt: the
same for every RELOCALIZATION edge of the last /map_graph (a piece of odometry found in the map).
The odometry is the base's (base_link), the keyframes are cameras."""
import sys

import rosbag


def quaternion_multiply(a, b):
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
            aw * bw - ax * bx - ay * by - az * bz)


def rotate(q, v):
    x, y, z, _ = quaternion_multiply(quaternion_multiply(q, (v[0], v[1], v[2], 0.0)),
                                     (-q[0], -q[1], -q[2], q[3]))
    return (x, y, z)


def pose_tuple(pose):
    p, q = pose.position, pose.orientation
    return ((p.x, p.y, p.z), (q.x, q.y, q.z, q.w))


def compose(a, b):
    (ta, qa), (tb, qb) = a, b
    r = rotate(qa, tb)
    return ((ta[0] + r[0], ta[1] + r[1], ta[2] + r[2]), quaternion_multiply(qa, qb))


def inverse(a):
    t, q = a
    qi = (-q[0], -q[1], -q[2], q[3])
    r = rotate(qi, t)
    return ((-r[0], -r[1], -r[2]), qi)


def tum_line(stamp, pose):
    (x, y, z), (qx, qy, qz, qw) = pose
    return (f"{stamp:.9f} {x:.9f} {y:.9f} {z:.9f} "
            f"{qx:.9f} {qy:.9f} {qz:.9f} {qw:.9f}\n")


def write_tum(path, entries):
    with open(path, "w") as out:
        out.write("# timestamp tx ty tz qx qy qz qw\n")
        for stamp, pose in entries:
            out.write(tum_line(stamp, pose))


RELOCALIZATION_EDGE = 2  # stereo_fabmap_slam/MapGraphEdge.RELOCALIZATION


def main(bag_path, odometry_path, keyframes_path, map_path=None, loops_path=None,
         relocalizations_path=None):
    counts, odometry, keyframes, loops = {}, [], {}, []  # keyframes: id -> [stamp, odom pose]
    map_poses, relocalizations = {}, []
    with rosbag.Bag(bag_path) as bag:
        for name, message, _ in bag.read_messages():
            counts[name] = counts.get(name, 0) + 1
            if name == "/odometry":
                odometry.append((message.header.stamp.to_sec(), pose_tuple(message.pose.pose)))
            elif name == "/keyframes":
                keyframes[message.id] = [message.header.stamp.to_sec(), pose_tuple(message.pose)]
            elif name == "/keyframe_updates":
                for kf_id, pose in zip(message.keyframe_ids, message.keyframe_poses):
                    if kf_id in keyframes:
                        keyframes[kf_id][1] = pose_tuple(pose)
            elif name == "/map_graph":
                map_poses = {kf_id: pose_tuple(pose)
                             for kf_id, pose in zip(message.keyframe_ids, message.keyframe_poses)}
                # The edge's "to" keyframe is the piece that was found, "from" the map's.
                relocalizations = [(edge.to_id, edge.from_id) for edge in message.edges
                                   if edge.type == RELOCALIZATION_EDGE]
            elif name == "/loop_edges":
                loops.append((message.query_id, message.match_id))
    write_tum(odometry_path, odometry)
    ordered = sorted(keyframes.items(), key=lambda entry: entry[1][0])
    write_tum(keyframes_path, [(stamp, map_poses.get(kf_id, pose)) for kf_id, (stamp, pose) in ordered])
    if map_path:
        corrected, k = [], -1
        for stamp, pose in odometry:
            while k + 1 < len(ordered) and ordered[k + 1][1][0] <= stamp + 1e-6:
                k += 1
            correction = ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0))
            if k >= 0 and ordered[k][0] in map_poses:
                kf_id, (_, odom_pose) = ordered[k]
                correction = compose(map_poses[kf_id], inverse(odom_pose))
            corrected.append((stamp, compose(correction, pose)))
        write_tum(map_path, corrected)
    if loops_path:
        with open(loops_path, "w") as out:
            out.write("# query_time match_time\n")
            for query, match in loops:
                if query in keyframes and match in keyframes:
                    out.write(f"{keyframes[query][0]:.9f} {keyframes[match][0]:.9f}\n")
    if relocalizations_path:
        with open(relocalizations_path, "w") as out:
            out.write("# query_time match_time\n")
            for query, match in relocalizations:
                if query in keyframes and match in keyframes:
                    out.write(f"{keyframes[query][0]:.9f} {keyframes[match][0]:.9f}\n")
    for name in sorted(counts):
        print(f"{name} {counts[name]}")
    return 0 if counts.get("/odometry") else 1


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:]))
