#!/usr/bin/env python3
"""Checks run_dataset's loops.csv against ground truth: for every accepted loop, the distance
between the two keyframes' positions (body frame of the ground truth, interpolated at the
keyframe times). Prints a JSON summary; exits 0 always (a report, not a test).

usage: check_loops.py LOOPS_CSV GROUND_TRUTH_CSV [--max-distance 1.0]
"""
import bisect
import csv
import json
import sys


def read_ground_truth(path):
    times, positions = [], []
    with open(path) as f:
        for line in f:
            if line.startswith('#') or not line.strip():
                continue
            fields = line.split(',')
            times.append(int(fields[0]) * 1e-9)
            positions.append(tuple(float(v) for v in fields[1:4]))
    return times, positions


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
    loops_path, truth_path = args
    times, positions = read_ground_truth(truth_path)
    accepted, far, distances = 0, 0, []
    with open(loops_path) as f:
        for row in csv.DictReader(f):
            if row['accepted'] != '1':
                continue
            accepted += 1
            p = position_at(times, positions, float(row['query_time']))
            q = position_at(times, positions, float(row['match_time']))
            if p is None or q is None:
                continue
            d = sum((a - b) ** 2 for a, b in zip(p, q)) ** 0.5
            distances.append(d)
            far += d > limit
    print(json.dumps({'accepted': accepted, 'checked': len(distances),
                      'max_distance_m': round(max(distances), 3) if distances else None,
                      'farther_than_limit': far, 'limit_m': limit}))


if __name__ == '__main__':
    main()
