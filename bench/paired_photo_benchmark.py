#!/usr/bin/env python3
"""Photo to pose and extraction, old build against new, in alternating rounds (issue #27).

Each round runs, for each of herz_jesu_p25's query photos 0002, 0012 and 0022 and each build in
turn, one process per photo: `cwloc-localize --image` (one thread; its wall time, the whole photo
to pose) and `cwloc-sift-bench --repeat 1` (decode + extraction in a fresh process). Alternating
the builds puts a shared machine's changing load on both; the table gives the medians over
photos and rounds and their ratio.

  bench/paired_photo_benchmark.py OLD_BIN NEW_BIN WORKDIR [--rounds 6] [--max-features 6000]
  bench/paired_photo_benchmark.py /tmp/old/build/bin build/bin /tmp/paired
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import time

TOP = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DATA = os.path.join(TOP, "..", "shared", "data", "herz_jesu_p25")
PHOTOS = ["0002.jpg", "0012.jpg", "0022.jpg"]
FOCAL = "1375.77"  # the dataset's calibrated focal length, as docs/benchmarks.md uses


def wall_ms(command):
    start = time.perf_counter()
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return (time.perf_counter() - start) * 1000


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("old_bin")
    parser.add_argument("new_bin")
    parser.add_argument("workdir")
    parser.add_argument("--rounds", type=int, default=6)
    parser.add_argument("--max-features", type=int, default=6000)
    args = parser.parse_args()
    if not os.path.isdir(DATA):
        sys.exit(f"paired_photo_benchmark: {DATA} not found (../shared/data)")
    os.makedirs(args.workdir, exist_ok=True)
    index = os.path.join(args.workdir, "herz_jesu_p25.cwl")
    if not os.path.exists(index):
        subprocess.run([os.path.join(args.new_bin, "cwloc-index"), "build", "--model",
                        os.path.join(DATA, "mapping_model", "bin"), "--database",
                        os.path.join(DATA, "database.db"), "-o", index],
                       check=True, stdout=subprocess.DEVNULL)
    builds = {"old": args.old_bin, "new": args.new_bin}
    pose = {name: [] for name in builds}
    extract = {name: [] for name in builds}
    for _ in range(args.rounds):
        for photo in PHOTOS:
            path = os.path.join(DATA, "query_images", photo)
            for name, bin_dir in builds.items():
                pose[name].append(wall_ms([
                    os.path.join(bin_dir, "cwloc-localize"), "--index", index, "--image", path,
                    "--focal", FOCAL, "--max-image-size", "1600", "--max-features",
                    str(args.max_features), "--threads", "1", "-o",
                    os.path.join(args.workdir, f"{name}.json")]))
                out = subprocess.run([
                    os.path.join(bin_dir, "cwloc-sift-bench"), "--max-num-features",
                    str(args.max_features), "--repeat", "1", path],
                    check=True, capture_output=True, text=True).stdout
                extract[name].append(float(out.splitlines()[1].split()[4]))  # total_ms
    n = args.rounds * len(PHOTOS)
    print(f"herz_jesu_p25 {', '.join(PHOTOS)}, {args.max_features} features, one thread, "
          f"{args.rounds} alternating rounds (medians of {n})\n")
    print("| | old ms | new ms | old / new |")
    print("|---|---|---|---|")
    rows = {}
    for label, times in (("photo to pose (cwloc-localize, one process)", pose),
                         ("decode + extraction (cwloc-sift-bench, one process)", extract)):
        old, new = statistics.median(times["old"]), statistics.median(times["new"])
        rows[label] = {"old_ms": old, "new_ms": new}
        print(f"| {label} | {old:.0f} | {new:.0f} | {old / new:.3f} |")
    with open(os.path.join(args.workdir, "paired.json"), "w") as f:
        json.dump(rows, f, indent=2)


if __name__ == "__main__":
    main()
