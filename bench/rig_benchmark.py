#!/usr/bin/python3
"""Rigs and multi-frame queries on real and generated data (docs/benchmarks.md, "Rigs").

For each data set (../shared/data's layout: mapping_model/bin, database.db holding the queries'
features, queries_gt.txt, queries_with_intrinsics.txt, scale_to_metres.txt), every held-out query
is localized alone (cwloc-localize --database --query-list), then grouped into frames:

  rig-K      K queries in name order, one frame (K = 2, 3, 4), their cam_from_rig from the full
             model's poses (cwloc-localize --frames)
  K crops    each query cut into K windows side by side (K = 3, 6; full height; the database's
             own SIFT features inside each): a narrow rig of one centre, whose single images
             are weak (as bench/make_zoomed_queries.py's crops)
  vio-K      K consecutive queries (K = 3, 5) with their relative poses disturbed as VIO drift
             would (0.1 deg and 0.5 %, or 0.5 deg and 2 % of each translation, 1 sigma), known
             scale and --frames-scale unknown (translations times a random factor in [0.5, 2]);
             only for sequences (--vio)

and a generated city's rigs of 2-6 cameras (cwloc-synth --rig-cameras, --rig rig_config.json,
its demo preset with 400 and with 120 features per image), whose frames include cameras that see
nothing and, with few features, frames no single image localizes.

Per kind of frame it prints: frames; frames any image localizes alone; frames the rig
localizes; frames an image localizes alone but the rig does not; frames the rig localizes of
those no image localizes alone, and of those where only one image matched; the median over
frames of the reference camera's position error (metres) for the rig, for the reference image
alone and for the best single image of each frame (an oracle's pick; the frames both localize);
the median time of the rig's pose stage; and a rig frame's total time minus its images'
localized alone (median and maximum over the frames all of whose images have a record alone),
ms. The images alone run twice, the first warming the page cache (the index is memory-mapped).
Last, for each rig-K frames file, hyperfine's median of the whole command against the same
images as a query list: the milliseconds a frame adds over its images localized alone.

    bench/rig_benchmark.py WORKDIR [DATASET ...] [--vio DATASET ...] [--synth N ...]
                           [--synth-features F ...]
    bench/rig_benchmark.py /tmp/rig herz_jesu_p25 sceaux_castle --vio fox_video --synth 2 4 6

DATASET: a folder, or a name in ../shared/data. Writes WORKDIR/NAME/{index.cwl, *.jsonl,
frames-*.txt}; the index is built once (cwloc-index's defaults).
"""
import argparse
import importlib.util
import json
import math
import os
import sqlite3
import statistics
import subprocess
import sys

import numpy as np

TOP = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BIN = os.environ.get("CWLOC_BIN", os.path.join(TOP, "build", "bin"))
SHARED = os.path.join(TOP, "..", "shared", "data")
TIMES = []  # (label, ms a rig frame adds over its images alone, spread)


def run(args, accept=(0, 1)):
    done = subprocess.run(args, capture_output=True, text=True)
    if done.returncode not in accept:
        sys.exit(f"{' '.join(args)}: exit {done.returncode}\n{done.stderr}")
    return done.stdout


def quaternion_matrix(q):
    w, x, y, z = q / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def matrix_quaternion(r):
    """(w, x, y, z) of a rotation matrix, w >= 0, from the symmetric 4 x 4 eigenproblem."""
    k = np.array([[r[0, 0] - r[1, 1] - r[2, 2], r[1, 0] + r[0, 1], r[2, 0] + r[0, 2], r[2, 1] - r[1, 2]],
                  [r[1, 0] + r[0, 1], r[1, 1] - r[0, 0] - r[2, 2], r[2, 1] + r[1, 2], r[0, 2] - r[2, 0]],
                  [r[2, 0] + r[0, 2], r[2, 1] + r[1, 2], r[2, 2] - r[0, 0] - r[1, 1], r[1, 0] - r[0, 1]],
                  [r[2, 1] - r[1, 2], r[0, 2] - r[2, 0], r[1, 0] - r[0, 1], r[0, 0] + r[1, 1] + r[2, 2]]]) / 3
    q = np.linalg.eigh(k)[1][:, -1]
    q = np.array([q[3], q[0], q[1], q[2]])
    return q if q[0] >= 0 else -q


def read_truth(data):
    """name -> (R, t, camera text) from queries_gt.txt."""
    truth = {}
    for line in open(os.path.join(data, "queries_gt.txt")):
        f = line.split()
        if f and not line.startswith("#"):
            truth[f[0]] = (quaternion_matrix(np.array([float(v) for v in f[1:5]])),
                           np.array([float(v) for v in f[5:8]]), " ".join(f[8:]))
    return truth


def metres_per_unit(data):
    for line in open(os.path.join(data, "scale_to_metres.txt")):
        f = line.split()
        if f and f[0] == "scale":
            return float(f[1])
    return 1.0


def rotation_vector_matrix(a):
    """exp([a]x), Rodrigues' formula."""
    angle = np.linalg.norm(a)
    if angle < 1e-15:
        return np.eye(3)
    k = a / angle
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(angle) * kx + (1 - math.cos(angle)) * kx @ kx


def centre(r, t):
    return -r.T @ t


def pose_of(record):
    return (quaternion_matrix(np.array(record["qvec"])), np.array(record["tvec"]))


def cam_from_rig(r, t, ref_r, ref_t):
    rc = r @ ref_r.T
    return rc, t - rc @ ref_t


def frame_line(frame, image, rc, tc, camera):
    q = matrix_quaternion(rc)
    return f"{frame} {image} {' '.join(repr(float(v)) for v in (*q, *tc))} {camera}\n"


def build_index(data, out):
    index = os.path.join(out, "index.cwl")
    if not os.path.exists(index):
        run([os.path.join(BIN, "cwloc-index"), "build", "--model",
             os.path.join(data, "mapping_model", "bin"), "--database",
             os.path.join(data, "database.db"), "-o", index])
    return index


def localize(index, args, out, accept=(0, 1)):
    run([os.path.join(BIN, "cwloc-localize"), "--index", index, "-q", "-o", out] + args, accept)
    return [json.loads(line) for line in open(out) if line.strip()]


class Table:
    def __init__(self):
        print("| data set | frames | any image alone | rig localized | rig lost, where one alone "
              "| rig, where none alone "
              "| rig, where one image matched "
              "| median error (m): rig / reference alone / best single | rig pose stage (ms) "
              "| rig total minus its images alone (ms): median, max |")
        print("|---|---|---|---|---|---|---|---|---|---|")

    @staticmethod
    def row(label, frames, singles, truth, scale):
        """frames: rig records; singles: name -> single record (success with pose) or None."""
        any_alone = rig_ok = none_alone = rig_took = one_seen = one_took = rig_lost = 0
        rig_errors, reference_errors, single_errors, extra, ratio = [], [], [], [], []
        for record in frames:
            names = [image["name"] for image in record["images"]]
            alone = [singles.get(n) for n in names]
            localized = [s for s in alone if s and s["success"] and "pose" in s]
            any_alone += bool(localized)
            none_alone += not localized
            one = sum(image["matches"]["correspondences"] > 0 for image in record["images"]) == 1
            one_seen += one
            rig_lost += bool(localized) and not record["success"]
            if record["success"]:
                rig_ok += 1
                rig_took += not localized
                one_took += one
            extra.append(record["times_ms"]["rig_pose"])
            if all(s and "times_ms" in s for s in alone):
                ratio.append(record["times_ms"]["total"] -
                             sum(s["times_ms"]["total"] for s in alone))
            if not (record["success"] and localized):
                continue
            error = lambda name, pose: scale * np.linalg.norm(
                centre(*pose_of(pose)) - centre(truth[name][0], truth[name][1]))
            rig_errors.append(error(names[0], record["pose"]))
            if alone[0] in localized:
                reference_errors.append(error(names[0], alone[0]["pose"]))
            # The best single image of the frame (an oracle's pick), each against its own truth.
            single_errors.append(min(error(s["name"], s["pose"]) for s in localized))
        med = lambda v: f"{statistics.median(v):.4g}" if v else "-"
        print(f"| {label} | {len(frames)} | {any_alone} | {rig_ok} | {rig_lost} | "
              f"{rig_took} of {none_alone} | "
              f"{one_took} of {one_seen} | "
              f"{med(rig_errors)} / {med(reference_errors)} / {med(single_errors)} | {med(extra)} | "
              f"{med(ratio)}, {max(ratio):.3g} |" if ratio else "- |")
        sys.stdout.flush()


def singles_of(index, data, out_dir):
    """Each query alone: name -> record. Run twice, the first to warm the page cache (the index
    is memory-mapped), so that the times compare with the rigs' that follow."""
    args = ["--database", os.path.join(data, "database.db"), "--query-list",
            os.path.join(data, "queries_with_intrinsics.txt")]
    out = os.path.join(out_dir, "singles.jsonl")
    # A generated rig's camera that sees nothing has no features: an error record (exit 2).
    localize(index, args, out, accept=(0, 1, 2))
    return {r["name"]: r for r in localize(index, args, out, accept=(0, 1, 2))}


def groups_in_order(names, k):
    return [names[i:i + k] for i in range(0, len(names) - k + 1, k)]


def timing(index, rig_args, alone_args, frames, out_dir, label):
    """hyperfine: the rig command against its images as single queries, whole commands in one
    run (index open and reading included): (ms per frame the rig adds, its spread)."""
    tool = [os.path.join(BIN, "cwloc-localize"), "--index", index, "-q", "-o", "/dev/null"]
    report = os.path.join(out_dir, f"timing-{label}.json")
    # -i: a generated rig's images that see nothing are error records (exit 2) alone.
    run(["hyperfine", "-N", "-i", "--warmup", "2", "--runs", "15", "--export-json", report,
         " ".join(tool + rig_args), " ".join(tool + alone_args)])
    rig, alone = json.load(open(report))["results"]
    extra = (rig["median"] - alone["median"]) * 1e3 / frames
    TIMES.append((label, extra, math.hypot(rig["stddev"], alone["stddev"]) * 1e3 / frames))


def time_frames_file(index, data, frames_path, out_dir, label):
    """timing() of a --frames file against its images as a query list."""
    lines = [line.split() for line in open(frames_path) if line.strip()]
    query_list = os.path.join(out_dir, f"timing-{os.path.basename(frames_path)}")
    with open(query_list, "w") as out:
        out.write("\n".join(" ".join([f[1]] + f[9:]) for f in lines) + "\n")
    database = ["--database", os.path.join(data, "database.db")]
    timing(index, database + ["--frames", frames_path], database + ["--query-list", query_list],
           len({f[0] for f in lines}), out_dir, label)


def rig_frames(index, data, out_dir, truth, names, k, label, noise=None, unknown=False, rng=None):
    path = os.path.join(out_dir, f"frames-{label}.txt")
    with open(path, "w") as out:
        for g, group in enumerate(groups_in_order(names, k)):
            scale = rng.uniform(0.5, 2.0) if unknown else 1.0
            ref_r, ref_t = truth[group[0]][:2]
            for name in group:
                rc, tc = cam_from_rig(*truth[name][:2], ref_r, ref_t)
                if noise and name != group[0]:
                    rc = rotation_vector_matrix(np.radians(rng.normal(0, noise[0], size=3))) @ rc
                    tc = tc + rng.normal(0, noise[1] * np.linalg.norm(tc), size=3)
                out.write(frame_line(f"f{g}", name, rc, scale * tc, truth[name][2]))
    args = ["--database", os.path.join(data, "database.db"), "--frames", path]
    if unknown:
        args += ["--frames-scale", "unknown"]
    return localize(index, args, os.path.join(out_dir, f"{label}.jsonl"))


def load_make_zoomed_queries():
    spec = importlib.util.spec_from_file_location(
        "make_zoomed_queries", os.path.join(TOP, "bench", "make_zoomed_queries.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def database_features(db, name):
    """The stored keypoints (N x 2) and descriptors (N x 128) of an image, or None."""
    row = db.execute("SELECT image_id FROM images WHERE name = ?", (name,)).fetchone()
    if row is None:
        return None
    zoomed = load_make_zoomed_queries()
    rows, cols, keypoints = zoomed.read_rows(db, "keypoints", row[0])
    _, _, descriptors = zoomed.read_rows(db, "descriptors", row[0])
    xy = np.frombuffer(keypoints, dtype="<f4").reshape(rows, cols)[:, :2] if rows else np.zeros((0, 2))
    d = np.frombuffer(descriptors, dtype=np.uint8).reshape(rows, 128) if rows else np.zeros((0, 128))
    return xy, d


def write_feature_file(path, xy, descriptors):
    """COLMAP's text feature file (scale 1, orientation 0: only x, y and the descriptor count)."""
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w") as out:
        out.write(f"{len(xy)} 128\n")
        for (x, y), d in zip(xy, descriptors):
            out.write(f"{float(x)!r} {float(y)!r} 1 0 " + " ".join(map(str, d)) + "\n")


def crop_features(data, out_dir, truth, parts):
    """`parts` windows side by side across each query's width (full height; 3: left, centre,
    right thirds) as COLMAP text feature files with their cameras: (feature dir, name -> [(crop,
    camera)])."""
    feature_dir = os.path.join(out_dir, f"crops-{parts}")
    db = sqlite3.connect(os.path.join(data, "database.db"))
    crops, list_lines = {}, []
    for name, (r, t, camera) in truth.items():
        features = database_features(db, name)
        if features is None:
            continue
        xy, descriptors = features
        f = camera.split()
        model, width, height = f[0], int(f[1]), int(f[2])
        params = [float(p) for p in f[3:]]
        w = width // parts
        crops[name] = []
        for part in range(parts):
            x0 = part * w
            crop = f"part{part}_{name}.txt"
            inside = (xy[:, 0] >= x0) & (xy[:, 0] < x0 + w)
            write_feature_file(os.path.join(feature_dir, crop), xy[inside] - [x0, 0],
                               descriptors[inside])
            cam = f"{model} {w} {height} {params[0]!r} {params[1] - x0!r} " + " ".join(
                repr(p) for p in params[2:])
            crops[name].append((crop, cam))
            list_lines.append(f"{crop} {cam}")
    with open(os.path.join(feature_dir, "list.txt"), "w") as out:
        out.write("\n".join(list_lines) + "\n")
    return feature_dir, crops


def dataset(arg, work, table, vio, rng):
    data = arg if os.path.isdir(arg) else os.path.join(SHARED, arg)
    name = os.path.basename(os.path.normpath(data))
    out_dir = os.path.join(work, name)
    os.makedirs(out_dir, exist_ok=True)
    index = build_index(data, out_dir)
    truth = read_truth(data)
    scale = metres_per_unit(data)
    names = sorted(truth)
    singles = singles_of(index, data, out_dir)
    for k in (2, 3, 4):
        if len(names) >= k:
            table.row(f"{name}, rig-{k}", rig_frames(index, data, out_dir, truth, names, k, f"rig-{k}"),
                      singles, truth, scale)
            time_frames_file(index, data, os.path.join(out_dir, f"frames-rig-{k}.txt"), out_dir,
                             f"{name}, rig-{k}")
    # Narrow rigs of crops: every crop of a photo shares its pose (cam_from_rig the identity).
    for parts in (3, 6):
        feature_dir, crops = crop_features(data, out_dir, truth, parts)
        crop_singles = {r["name"]: r for r in localize(
            index, ["--query-list", os.path.join(feature_dir, "list.txt")],
            os.path.join(out_dir, f"crop-{parts}-singles.jsonl"), accept=(0, 1, 2))}
        crop_truth = {c: (truth[n][0], truth[n][1], cam) for n, cs in crops.items() for c, cam in cs}
        path = os.path.join(out_dir, f"frames-crops-{parts}.txt")
        with open(path, "w") as out:
            for n, cs in crops.items():
                for c, cam in cs:
                    out.write(frame_line(n, c, np.eye(3), np.zeros(3), cam))
        frames = localize(index, ["--frames", path, "--image-dir", feature_dir],
                          os.path.join(out_dir, f"crops-{parts}.jsonl"))
        table.row(f"{name}, {parts} crops", frames, crop_singles, crop_truth, scale)
    if vio:
        for noise in ((0.1, 0.005), (0.5, 0.02)):
            for k in (3, 5):
                for unknown in (False, True):
                    label = f"vio-{k}-{noise[0]}deg" + ("-unknown-scale" if unknown else "")
                    table.row(f"{name}, {label}",
                              rig_frames(index, data, out_dir, truth, names, k, label,
                                         noise=noise, unknown=unknown, rng=rng),
                              singles, truth, scale)


def synth(cameras, features, work, table):
    out_dir = os.path.join(work, f"synth-rig{cameras}-{features}")
    city = os.path.join(out_dir, "city")
    if not os.path.exists(os.path.join(city, "rig_config.json")):
        run([os.path.join(BIN, "cwloc-synth"), "--preset", "demo", "--rig-cameras", str(cameras),
             "--queries", "30", "--features-per-image", str(features), "--overwrite", "-o", city])
    index = build_index(city, out_dir)
    truth = read_truth(city)
    singles = singles_of(index, city, out_dir)
    frames = localize(index, ["--rig", os.path.join(city, "rig_config.json"), "--database",
                              os.path.join(city, "database.db"), "--query-list",
                              os.path.join(city, "queries_with_intrinsics.txt")],
                      os.path.join(out_dir, "rig.jsonl"))
    table.row(f"generated city, {cameras}-camera rig, {features} features", frames, singles, truth,
              1.0)
    database = ["--database", os.path.join(city, "database.db"), "--query-list",
                os.path.join(city, "queries_with_intrinsics.txt")]
    timing(index, ["--rig", os.path.join(city, "rig_config.json")] + database, database,
           len(frames), out_dir, f"generated city, {cameras}-camera rig, {features} features")
    # Weak images (blur, low texture): each query image keeps every 6th of its features.
    db = sqlite3.connect(os.path.join(city, "database.db"))
    sparse_dir = os.path.join(out_dir, "sparse")
    lines = []
    for name, (r, t, camera) in truth.items():
        xy, descriptors = database_features(db, name)
        write_feature_file(os.path.join(sparse_dir, name + ".txt"), xy[::6], descriptors[::6])
        lines.append(f"{name}.txt {camera}")
    with open(os.path.join(sparse_dir, "list.txt"), "w") as out:
        out.write("\n".join(lines) + "\n")
    sparse_truth = {n + ".txt": v for n, v in truth.items()}
    sparse_singles = {r["name"]: r for r in localize(
        index, ["--query-list", os.path.join(sparse_dir, "list.txt")],
        os.path.join(out_dir, "sparse-singles.jsonl"), accept=(0, 1, 2))}
    frames = localize(index, ["--rig", os.path.join(city, "rig_config.json"), "--image-list",
                              os.path.join(sparse_dir, "list.txt")],
                      os.path.join(out_dir, "sparse-rig.jsonl"), accept=(0, 1, 2))
    table.row(f"generated city, {cameras}-camera rig, {features} features, 1/6 kept", frames,
              sparse_singles, sparse_truth, 1.0)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("work")
    parser.add_argument("datasets", nargs="*")
    parser.add_argument("--vio", nargs="*", default=[])
    parser.add_argument("--synth", nargs="*", type=int, default=[])
    # Features per generated image: the demo's 400, and fewer, where single images fail.
    parser.add_argument("--synth-features", nargs="*", type=int, default=[400, 120])
    args = parser.parse_args()
    rng = np.random.default_rng(1)
    table = Table()
    for arg in args.datasets:
        dataset(arg, args.work, table, False, rng)
    for arg in args.vio:
        dataset(arg, args.work, table, True, rng)
    for features in args.synth_features:
        for cameras in args.synth:
            synth(cameras, features, args.work, table)
    print("\n| frames (hyperfine, whole commands) | a rig frame minus its images alone, ms |")
    print("|---|---|")
    for label, extra, spread in TIMES:
        print(f"| {label} | {extra:+.2f} +- {spread:.2f} |")


if __name__ == "__main__":
    main()
