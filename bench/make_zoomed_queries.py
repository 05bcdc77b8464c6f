#!/usr/bin/python3
"""A telephoto-like query set from a data set's held-out queries: each query keeps only the
features inside a window of its image (COLMAP's own stored SIFT features, shifted into the
window's pixels), so the query becomes a narrow photo with the original focal length: a crop of
a third of a 1536 x 1024 photo is 512 x 341 pixels at f = 1376 px, f / width = 2.7, like a
zoomed internet photo. The poses are the originals'; the ground-truth camera is the original
with its principal point moved into the window. SIFT run on the cropped JPEG would give the
same features except within a few pixels of the window's border.

    bench/make_zoomed_queries.py DATASET_DIR OUT_DIR [--fraction 0.333] [--shift 0.0] [--photos]

--photos cuts the window out of the query's photo instead (DATASET_DIR/query_images/NAME, saved
as a JPEG of quality 95 without EXIF in OUT_DIR/query_images) and runs `colmap
feature_extractor` on it, so the query's SIFT features are the cropped photo's own, as a
zoomed photo's would be (needs python3-pil and colmap).

OUT_DIR gets a copy of the database in which each query image is replaced by its window (named
zoom_NAME, its own SIMPLE_RADIAL camera with the extractor's guess f = 1.2 max(w, h) and
prior_focal_length 0, as COLMAP gives a photo without EXIF), queries_gt.txt,
queries_with_intrinsics.txt, query_list.txt, scale_to_metres.txt, a link to the mapping model
and a README.txt: the layout bench/colmap_peer.sh reads. --shift moves each window off-centre
by that fraction of the free margin, alternating directions.
"""
import argparse
import os
import shutil
import sqlite3
import struct
import subprocess


def read_rows(db, table, image_id):
    row = db.execute(f"SELECT rows, cols, data FROM {table} WHERE image_id = ?", (image_id,)).fetchone()
    return row if row else (0, 0, b"")


def window_features(db, image_id, zoom, x0, y0, w, h):
    """The stored features inside the window, shifted into its pixels, as a new image."""
    rows, cols, keypoints = read_rows(db, "keypoints", image_id)
    drows, dcols, descriptors = read_rows(db, "descriptors", image_id)
    assert rows == drows and dcols == 128, f"{zoom}: {rows} keypoints, {drows} x {dcols} descriptors"
    kept_keypoints, kept_descriptors = [], []
    for r in range(rows):
        values = list(struct.unpack_from(f"<{cols}f", keypoints, 4 * cols * r))
        x, y = values[0] - x0, values[1] - y0
        if 0 <= x < w and 0 <= y < h:
            values[0], values[1] = x, y
            kept_keypoints.append(struct.pack(f"<{cols}f", *values))
            kept_descriptors.append(descriptors[128 * r:128 * (r + 1)])
    guess = 1.2 * max(w, h)
    camera = db.execute(
        "INSERT INTO cameras (model, width, height, params, prior_focal_length) VALUES (2, ?, ?, ?, 0)",
        (w, h, struct.pack("<4d", guess, w / 2, h / 2, 0.0))).lastrowid
    new_id = db.execute("INSERT INTO images (name, camera_id) VALUES (?, ?)", (zoom, camera)).lastrowid
    db.execute("INSERT INTO keypoints VALUES (?, ?, ?, ?)",
               (new_id, len(kept_keypoints), cols, b"".join(kept_keypoints)))
    db.execute("INSERT INTO descriptors VALUES (?, ?, 128, ?)",
               (new_id, len(kept_descriptors), b"".join(kept_descriptors)))
    return f"{len(kept_keypoints)} of {rows} features"


def crop_photo(source, box, target):
    """The window of the photo as a JPEG without EXIF (as an internet photo often is)."""
    from PIL import Image  # python3-pil; only this mode needs it
    os.makedirs(os.path.dirname(target), exist_ok=True)
    with Image.open(source) as photo:
        photo.convert("RGB").crop(box).save(target, quality=95)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("dataset")
    parser.add_argument("out")
    parser.add_argument("--fraction", type=float, default=1 / 3)
    parser.add_argument("--shift", type=float, default=0.0)
    parser.add_argument("--photos", action="store_true")
    args = parser.parse_args()
    if not 0.05 <= args.fraction <= 1:
        parser.error("--fraction must be in [0.05, 1]")
    os.makedirs(args.out, exist_ok=True)
    db_path = os.path.join(args.out, "database.db")
    shutil.copyfile(os.path.join(args.dataset, "database.db"), db_path)
    os.chmod(db_path, 0o644)
    for name in ("scale_to_metres.txt",):
        shutil.copyfile(os.path.join(args.dataset, name), os.path.join(args.out, name))
    link = os.path.join(args.out, "mapping_model")
    if not os.path.lexists(link):
        os.symlink(os.path.realpath(os.path.join(args.dataset, "mapping_model")), link)

    truth = {}
    for line in open(os.path.join(args.dataset, "queries_gt.txt")):
        fields = line.split()
        if fields and not line.startswith("#"):
            truth[fields[0]] = fields
    names = [line.split()[0] for line in open(os.path.join(args.dataset, "query_list.txt")) if line.strip()]

    db = sqlite3.connect(db_path)
    gt_lines, intrinsics_lines, list_lines = [], [], []
    for i, name in enumerate(names):
        image_id, camera_id = db.execute(
            "SELECT image_id, camera_id FROM images WHERE name = ?", (name,)).fetchone()
        fields = truth[name]
        model, width, height = fields[8], int(fields[9]), int(fields[10])
        params = [float(p) for p in fields[11:]]
        assert model == "SIMPLE_RADIAL", f"{name}: ground-truth camera {model}, expected SIMPLE_RADIAL"
        w, h = round(width * args.fraction), round(height * args.fraction)
        direction = 1 if i % 2 == 0 else -1
        x0 = round((width - w) / 2 * (1 + direction * args.shift))
        y0 = round((height - h) / 2 * (1 + direction * args.shift))
        zoom = "zoom_" + name
        if args.photos:
            crop_photo(os.path.join(args.dataset, "query_images", name), (x0, y0, x0 + w, y0 + h),
                       os.path.join(args.out, "query_images", zoom))
            kept = "SIFT on the cropped photo"
        else:
            kept = window_features(db, image_id, zoom, x0, y0, w, h)
        # The original query leaves the database: its matches with the mapping images too.
        for table in ("keypoints", "descriptors", "images"):
            db.execute(f"DELETE FROM {table} WHERE image_id = ?", (image_id,))
        for table in ("matches", "two_view_geometries"):
            db.execute(f"DELETE FROM {table} WHERE pair_id / 2147483647 = ? OR pair_id % 2147483647 = ?",
                       (image_id, image_id))
        focal, cx, cy, k = params
        camera_text = f"SIMPLE_RADIAL {w} {h} {focal!r} {cx - x0!r} {cy - y0!r} {k!r}"
        gt_lines.append(" ".join([zoom] + fields[1:8]) + " " + camera_text)
        intrinsics_lines.append(f"{zoom} {camera_text}")
        list_lines.append(zoom)
        print(f"{zoom}: window {w} x {h} at ({x0}, {y0}), {kept}, f / width {focal / w:.2f}")
    db.commit()
    db.close()
    if args.photos:
        # Each crop gets its own SIMPLE_RADIAL camera with COLMAP's guess f = 1.2 max(w, h).
        with open(os.path.join(args.out, "query_images", "list.txt"), "w") as out:
            out.write("\n".join(list_lines) + "\n")
        subprocess.run(["colmap", "feature_extractor", "--database_path", db_path,
                        "--image_path", os.path.join(args.out, "query_images"),
                        "--image_list_path", os.path.join(args.out, "query_images", "list.txt"),
                        "--ImageReader.camera_model", "SIMPLE_RADIAL", "--ImageReader.single_camera", "0",
                        "--SiftExtraction.use_gpu", "0"],
                       check=True, stdout=subprocess.DEVNULL, env=dict(os.environ, QT_QPA_PLATFORM="offscreen"))
    with open(os.path.join(args.out, "queries_gt.txt"), "w") as out:
        out.write("# The queries of " + os.path.realpath(args.dataset) + " cut to a window "
                  f"(bench/make_zoomed_queries.py --fraction {args.fraction} --shift {args.shift}).\n"
                  "# COLMAP convention: NAME QW QX QY QZ TX TY TZ MODEL W H PARAMS (world-to-camera).\n")
        out.write("\n".join(gt_lines) + "\n")
    with open(os.path.join(args.out, "queries_with_intrinsics.txt"), "w") as out:
        out.write("\n".join(intrinsics_lines) + "\n")
    with open(os.path.join(args.out, "query_list.txt"), "w") as out:
        out.write("\n".join(list_lines) + "\n")
    with open(os.path.join(args.out, "README.txt"), "w") as out:
        out.write("Zoomed queries made by bench/make_zoomed_queries.py from " +
                  os.path.realpath(args.dataset) + f" (--fraction {args.fraction} --shift {args.shift}):\n"
                  "each held-out query keeps the stored SIFT features inside a window of its photo.\n")


if __name__ == "__main__":
    main()
