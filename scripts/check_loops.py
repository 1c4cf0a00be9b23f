#!/usr/bin/env python3
"""Checks run_dataset's loops.csv against ground truth: for every accepted loop, the distance
between the two keyframes' positions (body frame of the ground truth, interpolated at the
keyframe times). Prints a JSON summary; exits 0 always (a report, not a test).

With --timing (the run's timing.csv, of a run that loaded no map: keyframe ids in the order
its keyframes were made), also the relocalizations that joined a segment to the map and the
candidates that never did, with their distances. With --revisits, the route's revisits by
ground truth (the body within 0.5 m and 45 deg of where it was at least 10 s before, for at
least 2 s) and the accepted loops whose query falls in each, per revisit and per 10 s of it.

usage: check_loops.py LOOPS_CSV GROUND_TRUTH_CSV [--max-distance 1.0] [--timing TIMING_CSV]
                      [--revisits]
"""
import bisect
import csv
import json
import math
import sys


def read_ground_truth(path, with_rotations=False):
    times, positions, rotations = [], [], []
    with open(path) as f:
        for line in f:
            if line.startswith('#') or not line.strip():
                continue
            fields = line.split(',')
            times.append(int(fields[0]) * 1e-9)
            positions.append(tuple(float(v) for v in fields[1:4]))
            if with_rotations:
                rotations.append(tuple(float(v) for v in fields[4:8]))  # w, x, y, z
    return (times, positions, rotations) if with_rotations else (times, positions)


def distance_at(times, positions, a, b):
    p = position_at(times, positions, a)
    q = position_at(times, positions, b)
    if p is None or q is None:
        return None
    return sum((x - y) ** 2 for x, y in zip(p, q)) ** 0.5


def relocalizations(timing_path, times, positions):
    """Relocalizations that joined a segment, and candidates that did not, with distances."""
    with open(timing_path) as f:
        rows = list(csv.DictReader(f))
    keyframe_times = [float(r['timestamp']) for r in rows if r['keyframe'] == '1']
    joins, candidates = [], []
    for row in rows:
        text = row['relocalization']
        if not text.startswith('success against keyframe '):
            continue
        keyframe = int(text.split('keyframe ')[1].split(':')[0])
        if keyframe >= len(keyframe_times):
            continue
        d = distance_at(times, positions, float(row['timestamp']), keyframe_times[keyframe])
        entry = {'time': round(float(row['timestamp']) - float(rows[0]['timestamp']), 2),
                 'keyframe': keyframe, 'distance_m': None if d is None else round(d, 2)}
        if 'a candidate, to be confirmed' in text or 'disagrees with the candidate' in text:
            candidates.append(entry)
        else:
            joins.append(entry)
    return joins, candidates


def rotation_angle(q, r):
    """The angle between two unit quaternions' rotations [deg]."""
    dot = abs(sum(a * b for a, b in zip(q, r)))
    return math.degrees(2 * math.acos(min(1.0, dot)))


def revisits(truth_path, loop_times):
    """Runs of at least 2 s where the body is within 0.5 m and 45 deg of a pose of >= 10 s
    before, with the accepted loops whose query lies in each (per 10 s too)."""
    times, positions, rotations = read_ground_truth(truth_path, with_rotations=True)
    step = max(1, len(times) // max(1, int((times[-1] - times[0]) * 10)))  # about 10 Hz
    t, p, r = times[::step], positions[::step], rotations[::step]
    revisited = []
    for i in range(len(t)):
        revisited.append(any(t[i] - t[j] >= 10 and math.dist(p[i], p[j]) < 0.5 and
                             rotation_angle(r[i], r[j]) < 45 for j in range(i)))
    runs, start = [], None
    for i, flag in enumerate(revisited + [False]):
        if flag and start is None:
            start = i
        if not flag and start is not None:
            if t[i - 1] - t[start] >= 2:
                runs.append((t[start], t[i - 1]))
            start = None
    result = []
    for a, b in runs:
        per_ten = []
        x = a
        while x < b:
            per_ten.append(sum(1 for q in loop_times if x <= q < min(x + 10, b + 1)))
            x += 10
        result.append({'from_s': round(a - times[0], 1), 'to_s': round(b - times[0], 1),
                       'loops': sum(1 for q in loop_times if a <= q <= b + 1),
                       'loops_per_10_s': per_ten})
    return result


def position_at(times, positions, t):
    i = bisect.bisect_left(times, t)
    if i <= 0 or i >= len(times):
        return None
    a, b = times[i - 1], times[i]
    w = (t - a) / (b - a) if b > a else 0.0
    return tuple(pa + w * (pb - pa) for pa, pb in zip(positions[i - 1], positions[i]))


def main():
    args = sys.argv[1:]
    limit = 1.0
    if '--max-distance' in args:
        k = args.index('--max-distance')
        limit = float(args[k + 1])
        del args[k:k + 2]
    timing_path = None
    if '--timing' in args:
        k = args.index('--timing')
        timing_path = args[k + 1]
        del args[k:k + 2]
    with_revisits = '--revisits' in args
    if with_revisits:
        args.remove('--revisits')
    loops_path, truth_path = args
    times, positions = read_ground_truth(truth_path)
    accepted, far, distances, loop_times = 0, 0, [], []
    with open(loops_path) as f:
        for row in csv.DictReader(f):
            if row['accepted'] != '1':
                continue
            accepted += 1
            loop_times.append(float(row['query_time']))
            d = distance_at(times, positions, float(row['query_time']), float(row['match_time']))
            if d is None:
                continue
            distances.append(d)
            far += d > limit
    summary = {'accepted': accepted, 'checked': len(distances),
               'max_distance_m': round(max(distances), 3) if distances else None,
               'farther_than_limit': far, 'limit_m': limit}
    if timing_path:
        joins, candidates = relocalizations(timing_path, times, positions)
        summary['relocalization_joins'] = joins
        summary['relocalization_joins_farther_than_limit'] = sum(
            1 for j in joins if j['distance_m'] is not None and j['distance_m'] > limit)
        summary['relocalization_candidates'] = candidates
    if with_revisits:
        summary['revisits'] = revisits(truth_path, loop_times)
    print(json.dumps(summary))


if __name__ == '__main__':
    main()
