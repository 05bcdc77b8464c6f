#!/usr/bin/python3
"""How far two COLMAP reconstructions of the same photos disagree (issue #66): the ground
truth's own spread, against which a localizer's error and its 95 % radius are read.

Each data set is made twice by bench/make_photo_dataset.sh with the same arguments (COLMAP
reconstructs a little differently each run). The second full model is aligned to the first by
a similarity (Umeyama) over the mapping images' centres; then for each query: how far its
ground-truth centre moved, next to cwloc's error against the first run's ground truth (and
COLMAP's registration's, and cwloc's position_radius95) from a bench/colmap_peer.sh run.

    bench/reconstruction_spread.py FIRST_DATASET SECOND_DATASET PEER_RUN [--results cwloc.jsonl]

Model units. Needs colmap (model_converter) and numpy.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

import numpy as np

TOP = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BIN = os.environ.get("CWLOC_BIN", os.path.join(TOP, "build", "bin"))
sys.path.insert(0, os.path.join(TOP, "bench"))
from rig_benchmark import centre, quaternion_matrix  # noqa: E402


def centres(model_bin):
    """Image name -> camera centre of a COLMAP binary model."""
    with tempfile.TemporaryDirectory() as text:
        subprocess.run(["colmap", "model_converter", "--input_path", model_bin, "--output_path",
                        text, "--output_type", "TXT"], capture_output=True, check=True)
        lines = [l for l in open(os.path.join(text, "images.txt")) if not l.startswith("#")]
    out = {}
    for line in lines[0::2]:  # a pose line, then a points line
        f = line.split()
        out[f[9]] = centre(quaternion_matrix(np.array([float(v) for v in f[1:5]])),
                           np.array([float(v) for v in f[5:8]]))
    return out


def similarity(source, target):
    """scale, R, t minimizing |scale R source + t - target| (Umeyama)."""
    ms, mt = source.mean(0), target.mean(0)
    s, d = source - ms, target - mt
    u, sigma, vt = np.linalg.svd(d.T @ s / len(source))
    flip = np.eye(3)
    if np.linalg.det(u @ vt) < 0:
        flip[2, 2] = -1
    rotation = u @ flip @ vt
    scale = np.trace(np.diag(sigma) @ flip) / s.var(0).sum()
    return scale, rotation, mt - scale * rotation @ ms


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("first")
    parser.add_argument("second")
    parser.add_argument("peer_run", help="bench/colmap_peer.sh's WORKDIR for the first data set")
    parser.add_argument("--results", default="cwloc.jsonl", help="cwloc's records in PEER_RUN")
    args = parser.parse_args()
    a = centres(os.path.join(args.first, "full_model", "bin"))
    b = centres(os.path.join(args.second, "full_model", "bin"))
    queries = [l.split()[0] for l in open(os.path.join(args.first, "query_list.txt")) if l.strip()]
    common = [n for n in a if n in b and n not in queries]
    if len(common) < 3:
        sys.exit(f"{args.second}: {len(common)} mapping images in common with {args.first}")
    scale, rotation, shift = similarity(np.array([b[n] for n in common]),
                                        np.array([a[n] for n in common]))
    moved = {n: np.linalg.norm(scale * rotation @ b[n] + shift - a[n]) for n in a if n in b}
    results = os.path.join(args.peer_run, args.results)
    report = json.loads(subprocess.run(
        [os.path.join(BIN, "cwloc-eval"), "--gt", os.path.join(args.first, "queries_gt.txt"),
         "--json", "--results", results, "--label", "cwloc",
         "--results", os.path.join(args.peer_run, "colmap_poses.txt"), "--label", "colmap"],
        capture_output=True, text=True, check=True).stdout)
    per = {r["label"]: {q["name"]: q for q in r["per_query"]} for r in report["runs"]}
    records = {json.loads(l)["name"]: json.loads(l) for l in open(results) if l.strip()}
    mapping = [moved[n] for n in common]
    print(f"{os.path.basename(os.path.normpath(args.first))}: the mapping images' centres moved "
          f"median {np.median(mapping):.4f}, most {max(mapping):.4f} ({len(common)} images)")
    print("| query | ground truth moved | cwloc error | COLMAP error | cwloc radius95 |")
    print("|---|---|---|---|---|")
    for q in queries:
        if q not in moved:
            continue
        cells = [per[label].get(q, {}).get("position_error") for label in ("cwloc", "colmap")]
        radius = (records.get(q, {}).get("covariance") or {}).get("position_radius95")
        text = ["-" if v is None else f"{v:.4f}" for v in cells + [radius]]
        print(f"| {q} | {moved[q]:.4f} | " + " | ".join(text) + " |")


if __name__ == "__main__":
    main()
