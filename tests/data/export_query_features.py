#!/usr/bin/env python3
"""Writes images of a COLMAP database as COLMAP text feature files (what --features reads).

Usage: export_query_features.py DATABASE OUTPUT_DIR IMAGE_NAME...

Writes OUTPUT_DIR/IMAGE_NAME.txt: 'N 128', then 'X Y SCALE ORIENTATION D_1 ... D_128' per
keypoint in the database's row order. X and Y are the stored float32 values (printed so that they
read back exactly); SCALE and ORIENTATION follow COLMAP's FeatureKeypoint from the 6-column
affine shape (a11 a12 a21 a22): scale = mean of |(a11, a21)| and |(a12, a22)|,
orientation = atan2(a21, a11). Standard library only; opens the database read-only.
"""
import math
import sqlite3
import struct
import sys
from pathlib import Path


def main():
    if len(sys.argv) < 4:
        sys.exit(__doc__)
    database, out_dir, names = sys.argv[1], Path(sys.argv[2]), sys.argv[3:]
    out_dir.mkdir(parents=True, exist_ok=True)
    db = sqlite3.connect(f"file:{database}?mode=ro", uri=True)
    for name in names:
        row = db.execute("SELECT image_id FROM images WHERE name = ?", (name,)).fetchone()
        if row is None:
            sys.exit(f"{database}: no image named '{name}'")
        image_id = row[0]
        rows, cols, keypoints = db.execute(
            "SELECT rows, cols, data FROM keypoints WHERE image_id = ?", (image_id,)).fetchone()
        drows, dcols, descriptors = db.execute(
            "SELECT rows, cols, data FROM descriptors WHERE image_id = ?", (image_id,)).fetchone()
        if cols != 6 or dcols != 128 or drows != rows:
            sys.exit(f"{database}: '{name}': expected N x 6 keypoints and N x 128 descriptors")
        values = struct.unpack(f"<{rows * 6}f", keypoints)
        lines = [f"{rows} 128"]
        for i in range(rows):
            x, y, a11, a12, a21, a22 = values[6 * i:6 * i + 6]
            scale = 0.5 * (math.hypot(a11, a21) + math.hypot(a12, a22))
            orientation = math.atan2(a21, a11)
            descriptor = " ".join(str(b) for b in descriptors[128 * i:128 * i + 128])
            lines.append(f"{x:.9g} {y:.9g} {scale:.6g} {orientation:.6g} {descriptor}")
        (out_dir / f"{name}.txt").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
