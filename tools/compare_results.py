#!/usr/bin/env python3
"""Compares two cwloc-localize JSON-lines outputs of the same queries, e.g. from an x86-64 and
an aarch64 build: the same localized set, the same inlier and correspondence counts, poses
(qvec, tvec) and estimated cameras within a relative tolerance, and 95 % position radii of the
pose covariances within 100 times it (they square the residuals the poses leave).

Usage: compare_results.py A.jsonl B.jsonl [--rel 1e-6]
Exit 0 when they agree, 1 with one line per difference otherwise.
"""
import argparse
import json
import sys


def load(path):
    records = {}
    with open(path) as f:
        for line in f:
            record = json.loads(line)
            records[record["name"]] = record
    return records


def close(a, b, rel):
    """|a - b| <= rel * max(|a|, |b|, 1) elementwise: relative for large values, absolute near 0."""
    return len(a) == len(b) and all(abs(x - y) <= rel * max(abs(x), abs(y), 1.0) for x, y in zip(a, b))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("a")
    parser.add_argument("b")
    parser.add_argument("--rel", type=float, default=1e-6)
    args = parser.parse_args()
    a, b = load(args.a), load(args.b)
    problems = []
    if set(a) != set(b):
        problems.append(f"different queries: only in A {sorted(set(a) - set(b))}, "
                        f"only in B {sorted(set(b) - set(a))}")
    worst = 0.0
    for name in sorted(set(a) & set(b)):
        ra, rb = a[name], b[name]
        if ra.get("success") != rb.get("success"):
            problems.append(f"{name}: localized {ra.get('success')} vs {rb.get('success')}")
            continue
        for key in ("num_inliers",):
            if ra.get(key) != rb.get(key):
                problems.append(f"{name}: {key} {ra.get(key)} vs {rb.get(key)}")
        if ra.get("matches", {}).get("correspondences") != rb.get("matches", {}).get("correspondences"):
            problems.append(f"{name}: correspondences {ra['matches']['correspondences']} vs "
                            f"{rb['matches']['correspondences']}")
        if not ra.get("success"):
            continue
        values_a = ra["pose"]["qvec"] + ra["pose"]["tvec"] + ra["camera"]["params"]
        values_b = rb["pose"]["qvec"] + rb["pose"]["tvec"] + rb["camera"]["params"]
        if not close(values_a, values_b, args.rel):
            problems.append(f"{name}: pose or camera differs beyond {args.rel}: {values_a} vs {values_b}")
        else:
            worst = max([worst] + [abs(x - y) / max(abs(x), abs(y), 1.0)
                                   for x, y in zip(values_a, values_b)])
        radius_a = ra.get("covariance", {}).get("position_radius95")
        radius_b = rb.get("covariance", {}).get("position_radius95")
        if (radius_a is None) != (radius_b is None) or (
                radius_a is not None and abs(radius_a - radius_b) > 100 * args.rel * max(radius_a, radius_b)):
            problems.append(f"{name}: position_radius95 {radius_a} vs {radius_b}")
    for line in problems:
        print(line)
    localized = sum(1 for r in a.values() if r.get("success"))
    print(f"compare_results: {len(a)} queries, {localized} localized in A; "
          f"{'agree' if not problems else f'{len(problems)} difference(s)'}; "
          f"largest relative difference {worst:.3g}")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
