#!/usr/bin/env python3
"""Localizes an hloc query list with cwloc on a thread pool, and writes the poses as
visuallocalization.net wants them (what `cwloc-localize --poses` writes):

    python3 localize_hloc_list.py --index model.cwl --queries queries_with_intrinsics.txt \\
        --images images/ --poses poses.txt [--jsonl results.jsonl] [--threads 4] \\
        [-O max_image_size=1600 -O max_features=6000]

The list has one query per line, `NAME MODEL W H PARAMS...` (hloc's queries_with_intrinsics.txt)
or just `NAME` (the EXIF focal length, else an estimated one). Each -O is a cwloc-localize
option with '-' written '_', its value as that flag takes it. Pose lines are
`NAME QW QX QY QZ TX TY TZ` (COLMAP's cam_from_world) for the localized queries, in list order.
"""
import argparse
import os
import sys
from concurrent.futures import ThreadPoolExecutor

import cwloc


def read_queries(path):
    queries = []
    with open(path) as lines:
        for line in lines:
            fields = line.split(maxsplit=1)
            if fields and not fields[0].startswith("#"):
                queries.append((fields[0], fields[1].strip() if len(fields) > 1 else None))
    return queries


def pose_line(name, result):
    # "%.17g" as cwloc-localize's PoseLine prints them: every double read back exactly.
    numbers = [*result.rotation.tolist(), *result.translation.tolist()]
    return name + "".join(" %.17g" % x for x in numbers) + "\n"


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--index", required=True)
    parser.add_argument("--queries", required=True, help="hloc query list")
    parser.add_argument("--images", required=True, help="folder the names are relative to")
    parser.add_argument("--poses", required=True, help="pose file to write")
    parser.add_argument("--jsonl", help="also write cwloc-localize's JSON record per query")
    parser.add_argument("--threads", type=int, default=os.cpu_count())
    parser.add_argument("-O", dest="options", action="append", default=[], metavar="NAME=VALUE")
    args = parser.parse_args()
    options = dict(option.split("=", 1) for option in args.options)

    localizer = cwloc.Localizer.open(args.index)
    queries = read_queries(args.queries)

    def localize(query):
        name, camera = query
        return localizer.localize_photo(os.path.join(args.images, name), camera, **options)

    with ThreadPoolExecutor(max_workers=args.threads) as pool:
        results = list(pool.map(localize, queries))

    with open(args.poses, "w") as poses:
        for (name, _), result in zip(queries, results):
            if result.success:
                poses.write(pose_line(name, result))
    if args.jsonl:
        with open(args.jsonl, "w") as jsonl:
            jsonl.writelines(result.json + "\n" for result in results)
    localized = sum(result.success for result in results)
    print(f"{localized} of {len(results)} queries localized", file=sys.stderr)
    return 0 if localized == len(results) else 1


if __name__ == "__main__":
    sys.exit(main())
