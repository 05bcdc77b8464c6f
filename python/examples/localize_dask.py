#!/usr/bin/env python3
"""Localizes a folder of photos on a Dask cluster and writes cwloc-localize's JSON lines.

    python3 localize_dask.py --index city.cwl --images photos/ -o results.jsonl --workers 2
    python3 localize_dask.py --index /shared/city.cwl --images /shared/photos \\
        --scheduler tcp://scheduler-host:8786 -o results.jsonl

Without --scheduler it starts a local cluster of --workers processes, one thread each. On a
real cluster the index and the photos must be readable on every worker at the paths given
(docs/python.md). Prints the photos per second, counted from the first photo sent to the last
record back (the cluster's start and each worker's index opening included).
"""
import argparse
import json
import sys
import time
from pathlib import Path

from dask.distributed import Client, LocalCluster

import cwloc.dask


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--index", required=True)
    parser.add_argument("--images", required=True, type=Path, help="a folder of JPEG or PNG photos")
    parser.add_argument("-o", "--output", required=True, type=Path)
    parser.add_argument("--scheduler", help="a running scheduler's address; else a local cluster")
    parser.add_argument("--workers", type=int, default=2, help="local cluster processes")
    parser.add_argument("--repeat", type=int, default=1, help="send every photo this many times")
    parser.add_argument("--camera", help="hloc's 'MODEL W H PARAMS' for every photo")
    parser.add_argument("--option", action="append", default=[], metavar="NAME=VALUE",
                        help="a cwloc-localize option, e.g. max_features=6000")
    args = parser.parse_args()
    photos = sorted(str(p) for p in args.images.iterdir()
                    if p.suffix.lower() in (".jpg", ".jpeg", ".png")) * args.repeat
    options = dict(option.split("=", 1) for option in args.option)

    cluster = None
    if args.scheduler:
        client = Client(args.scheduler)
    else:
        cluster = LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True,
                               dashboard_address=None)
        client = Client(cluster)
    start = time.perf_counter()
    records = cwloc.dask.localize_many(client, args.index, photos, camera=args.camera, **options)
    seconds = time.perf_counter() - start
    client.close()
    if cluster is not None:
        cluster.close()

    with open(args.output, "w") as out:
        for record in records:
            out.write(json.dumps(record) + "\n")
    localized = sum(1 for r in records if r["success"])
    workers = args.scheduler or f"{args.workers} local workers"
    print(f"{localized} of {len(records)} photos localized on {workers} in {seconds:.2f} s: "
          f"{len(records) / seconds:.2f} photos/s")
    return 0 if localized == len(records) else 1


if __name__ == "__main__":
    sys.exit(main())
