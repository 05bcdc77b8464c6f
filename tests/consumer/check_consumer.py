#!/usr/bin/env python3
"""Installs a built cwloc tree into a fresh prefix, builds the consumer apps of this folder
against it with find_package(cwloc), runs them (C++ and C) on the golden index shipped in
tests/data, and checks that both localize its query near the ground truth with the same pose.

Usage: check_consumer.py BUILD_DIR SOURCE_DIR
"""
import math
import subprocess
import sys
import tempfile
from pathlib import Path


def run(*args, **kwargs):
    result = subprocess.run([str(a) for a in args], capture_output=True, text=True, **kwargs)
    if result.returncode != 0:
        sys.exit(f"check_consumer: {' '.join(map(str, args))} failed ({result.returncode}):\n"
                 f"{result.stdout}{result.stderr}")
    return result.stdout


def main():
    build, source = Path(sys.argv[1]).resolve(), Path(sys.argv[2]).resolve()
    with tempfile.TemporaryDirectory(prefix="cwloc-consumer-") as tmp:
        prefix, consumer_build = Path(tmp) / "prefix", Path(tmp) / "build"
        run("cmake", "--install", build, "--prefix", prefix)
        expected = ["include/cwloc/cwloc.hpp", "include/cwloc/cwloc.h", "lib/libcwloc.so",
                    "lib/cmake/cwloc/cwlocConfig.cmake", "lib/cmake/cwloc/cwlocConfigVersion.cmake",
                    "lib/cmake/cwloc/cwlocTargets.cmake", "bin/cwloc-localize", "bin/cwloc-index"]
        missing = [p for p in expected if not (prefix / p).exists()]
        if missing:
            sys.exit(f"check_consumer: the install lacks {missing}")

        run("cmake", "-S", source / "tests" / "consumer", "-B", consumer_build, "-G", "Ninja",
            f"-DCMAKE_PREFIX_PATH={prefix}", "-DCMAKE_BUILD_TYPE=Release")
        run("cmake", "--build", consumer_build)

        golden = source / "tests" / "data" / "golden"
        queries = golden / "index-1.0-queries"
        scale = next(float(line.split()[1]) for line in (queries / "scale_to_metres.txt").open()
                     if line.startswith("scale "))
        worst = 0.0
        for line in (queries / "queries_gt.txt").open():
            if line.startswith("#") or not line.strip():
                continue
            fields = line.split()
            name, q, t, camera = fields[0], list(map(float, fields[1:5])), list(map(float, fields[5:8])), fields[8:]
            outputs = [run(consumer_build / app, golden / "index-1.0.cwl",
                           queries / f"{name}.txt", *camera)
                       for app in ("consumer_cpp", "consumer_c")]
            if outputs[0] != outputs[1]:
                sys.exit(f"check_consumer: {name}: C++ and C disagree:\n{outputs[0]}{outputs[1]}")
            words = outputs[0].split()
            center = list(map(float, words[1:4]))
            worst = max(worst, math.dist(center, true_center(q, t)) * scale)
        if worst > 0.25:
            sys.exit(f"check_consumer: worst position error {worst:.3f} m > 0.25 m")
        print(f"check_consumer: installed, built C++ and C consumers, 4 queries agree, "
              f"worst position error {worst:.4f} m")


def true_center(q, t):
    """C = -R(q)^T t for COLMAP's q = (w, x, y, z)."""
    w, x, y, z = q
    r = [[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
         [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
         [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]]
    return [-sum(r[i][j] * t[i] for i in range(3)) for j in range(3)]


if __name__ == "__main__":
    main()
