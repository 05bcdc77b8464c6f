#!/usr/bin/env python3
"""Tiles against their whole index (docs/benchmarks.md, "Tiles").

For each index, extracts the tile of a region with `cwloc-index extract --near`, then localizes
the generated city's queries whose true position lies in the region (queries_geo.txt) on the
whole index with the region as --prior-position and on the tile alone, in alternating rounds on
one thread. Prints a markdown table: sizes, extraction time, localized queries, how many poses
are bit-identical and the largest difference, median errors and times, peak memory.

Usage: bench/tile_benchmark.py WORKDIR CITY "LAT LON RADIUS_M" INDEX... [--rounds 3] [--bin DIR]
"""
import argparse
import json
import math
import os
import statistics
import subprocess
import sys


def run(command, **kwargs):
    return subprocess.run(command, check=True, capture_output=True, text=True, **kwargs).stdout


def queries_inside(city, lat0, lon0, radius, out_path):
    # A local tangent plane is exact enough for a few hundred metres.
    metres_lat = 111132.954 - 559.822 * math.cos(2 * math.radians(lat0))
    metres_lon = 111412.84 * math.cos(math.radians(lat0))
    inside = set()
    for line in open(f"{city}/queries_geo.txt"):
        if line.startswith("#") or not line.strip():
            continue
        name, lat, lon, _ = line.split()
        if math.hypot((float(lat) - lat0) * metres_lat, (float(lon) - lon0) * metres_lon) < radius:
            inside.add(name)
    with open(out_path, "w") as out:
        for line in open(f"{city}/queries_with_intrinsics.txt"):
            if line.split() and line.split()[0] in inside:
                out.write(line)
    return len(inside)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("work")
    parser.add_argument("city")
    parser.add_argument("region")
    parser.add_argument("indexes", nargs="+")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--bin", default=os.path.join(os.path.dirname(__file__), "..", "build", "bin"))
    args = parser.parse_args()
    os.makedirs(args.work, exist_ok=True)
    lat0, lon0, radius = map(float, args.region.split())
    queries = f"{args.work}/inside.txt"
    count = queries_inside(args.city, lat0, lon0, radius, queries)
    # Metres per model unit: a similarity's "scale S" line, or the number alone.
    fields = next(line.split() for line in open(f"{args.city}/scale_to_metres.txt")
                  if line.strip() and not line.startswith("#"))
    metres = float(fields[-1] if fields[0] == "scale" else fields[0])
    rows = []
    for index in args.indexes:
        name = os.path.splitext(os.path.basename(index))[0]
        tile = f"{args.work}/{name}-tile.cwl"
        report = json.loads(run([f"{args.bin}/cwloc-index", "extract", "--index", index, "--near",
                                 args.region, "-o", tile, "--json"]))
        runs = {"whole": ([index, ["--prior-position", args.region]]), "tile": ([tile, []])}
        records, rss = {k: [] for k in runs}, {k: [] for k in runs}
        for r in range(args.rounds):
            for kind, (path, extra) in runs.items():
                out = f"{args.work}/{name}-{kind}.round{r + 1}.jsonl"
                peak = subprocess.run(
                    ["/usr/bin/time", "-f", "%M", f"{args.bin}/cwloc-localize", "--index", path,
                     "--database", f"{args.city}/database.db", "--query-list", queries,
                     "--threads", "1", "-q", "-o", out] + extra, capture_output=True, text=True)
                if peak.returncode not in (0, 1):
                    sys.exit(peak.stderr)
                rss[kind].append(int(peak.stderr.strip().splitlines()[-1]) / 1024)
                records[kind].append([json.loads(line) for line in open(out)])
        evals = {}
        for kind in runs:
            text = run([f"{args.bin}/cwloc-eval", "--results",
                        f"{args.work}/{name}-{kind}.round1.jsonl", "--gt",
                        f"{args.city}/queries_gt.txt", "--scale", f"{args.city}/scale_to_metres.txt",
                        "--json"])
            evals[kind] = json.loads(text)["runs"][0]
        identical, largest = 0, 0.0
        for a, b in zip(records["whole"][0], records["tile"][0]):
            if a["success"] and b["success"]:
                identical += a["pose"] == b["pose"]
                largest = max(largest, metres * math.dist(a["pose"]["center"], b["pose"]["center"]))
        times = {k: statistics.median(r["times_ms"]["total"] for rnd in records[k] for r in rnd)
                 for k in runs}
        localized = {k: evals[k]["localized"] for k in runs}
        both = sum(1 for a, b in zip(records["whole"][0], records["tile"][0])
                   if a["success"] and b["success"])
        whole_mb = os.path.getsize(index) / 1e6
        rows.append(
            f"| {name} | {whole_mb:.1f} MB | {report['file_bytes'] / 1e6:.1f} MB "
            f"({report['counts']['images']} of {report['parent']['images']} images) | "
            f"{report['seconds']:.2f} | {localized['whole']} / {localized['tile']} of {count} | "
            f"{identical} of {both}, others within {100 * largest:.1f} cm | "
            f"{evals['whole']['position_error']['median']:.4f} / "
            f"{evals['tile']['position_error']['median']:.4f} | "
            f"{times['whole']:.2f} / {times['tile']:.2f} | "
            f"{statistics.median(rss['whole']):.0f} / {statistics.median(rss['tile']):.0f} MB |")
    print(f"Region '{args.region}': {count} queries inside; whole index with that position prior / "
          f"tile alone, one thread, {args.rounds} alternating rounds (medians).\n")
    print("| index | whole | tile | extract s | localized | identical poses | median error m | "
          "median ms | peak RSS |")
    print("|---|---|---|---|---|---|---|---|---|")
    print("\n".join(rows))


if __name__ == "__main__":
    main()
