#!/usr/bin/env bash
# A real-photo data set from a folder of photos, reconstructed by the real `colmap`, in the layout
# the benchmarks read (bench/colmap_peer.sh, paper_experiments.sh): every photo keeps its own
# camera, as in an internet collection where each photo comes from a different camera, and
# every Nth registered photo (in name order) is held out as a query.
#
#   bench/make_photo_dataset.sh PHOTOS_DIR OUT_DIR [--query-every N] [--query-offset I]
#       [--max-image-size PX] [--max-features N] [--single-camera]
#
# The queries are the registered photos I, I + N, I + 2N, ... in name order (I defaults to N / 2);
# data sets made with offsets 0 .. N-1 hold every photo out once.
#
# Steps (colmap 3.8, CPU, all cores):
#   feature_extractor   SIMPLE_RADIAL per photo (--single-camera: one for all); a photo without
#                       EXIF gets COLMAP's guess f = 1.2 max(w, h), prior_focal_length 0
#   exhaustive_matcher  every pair, geometric verification
#   mapper              the largest model is the full model (ground truth)
#   image_deleter       mapping model = full model minus the queries
# Then OUT_DIR holds database.db (every photo: features and matches; a localizer must not use
# the queries' matches, and bench/colmap_peer.sh drops them), full_model/bin,
# mapping_model/{bin,txt}, query_list.txt, queries_gt.txt (the full model's poses and cameras),
# queries_with_intrinsics.txt, query_images/ (links), scale_to_metres.txt (model units),
# stats.json, logs/ and README.txt with the commands. PHOTOS_DIR is only read.
set -euo pipefail
usage="usage: $0 PHOTOS_DIR OUT_DIR [--query-every N] [--query-offset I] [--max-image-size PX] [--max-features N] [--single-camera]"
[ $# -ge 2 ] || { echo "$usage" >&2; exit 2; }
photos="$(realpath "$1")"
out="$(realpath -m "$2")"
shift 2
query_every=6
query_offset=""
max_image_size=1600
max_features=8192
single_camera=0
while [ $# -gt 0 ]; do
  case "$1" in
    --query-every) query_every="$2"; shift 2 ;;
    --query-offset) query_offset="$2"; shift 2 ;;
    --max-image-size) max_image_size="$2"; shift 2 ;;
    --max-features) max_features="$2"; shift 2 ;;
    --single-camera) single_camera=1; shift ;;
    *) echo "$0: unknown option $1" >&2; echo "$usage" >&2; exit 2 ;;
  esac
done
[ -d "$photos" ] || { echo "$0: $photos is not a directory" >&2; exit 2; }
[[ "$query_every" =~ ^[0-9]+$ ]] && [ "$query_every" -ge 2 ] ||
  { echo "$0: --query-every must be an integer >= 2, got $query_every" >&2; exit 2; }
query_offset="${query_offset:-$((query_every / 2))}"
[[ "$query_offset" =~ ^[0-9]+$ ]] && [ "$query_offset" -lt "$query_every" ] ||
  { echo "$0: --query-offset must be an integer in [0, $query_every), got $query_offset" >&2; exit 2; }
[ ! -e "$out/database.db" ] || { echo "$0: $out/database.db exists; choose a new OUT_DIR" >&2; exit 2; }
mkdir -p "$out/logs" "$out/full_model/bin" "$out/mapping_model/bin" "$out/mapping_model/txt" \
  "$out/query_images" "$out/sparse"
export QT_QPA_PLATFORM=offscreen   # colmap is a Qt program; no X server here
db="$out/database.db"

run() {   # run NAME CMD...: CMD's output in logs/NAME.log, its wall time in logs/NAME.time
  local name="$1" t0
  shift
  echo "## $name"
  t0="$(date +%s.%N)"
  "$@" >"$out/logs/$name.log" 2>&1 || { echo "$0: $name failed, see $out/logs/$name.log" >&2; exit 1; }
  awk -v a="$t0" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1f s\n", b - a }' | tee "$out/logs/$name.time"
}

run feature_extractor colmap feature_extractor --database_path "$db" --image_path "$photos" \
  --ImageReader.camera_model SIMPLE_RADIAL --ImageReader.single_camera "$single_camera" \
  --SiftExtraction.use_gpu 0 --SiftExtraction.max_image_size "$max_image_size" \
  --SiftExtraction.max_num_features "$max_features"
run exhaustive_matcher colmap exhaustive_matcher --database_path "$db" --SiftMatching.use_gpu 0
run mapper colmap mapper --database_path "$db" --image_path "$photos" --output_path "$out/sparse"
# The largest model (most registered images) is the ground truth.
best=""
best_count=-1
for model in "$out"/sparse/*/; do
  count="$(colmap model_analyzer --path "$model" 2>&1 | awk '/Registered images/ { print $NF }')"
  if [ "${count:-0}" -gt "$best_count" ]; then best="$model" best_count="$count"; fi
done
[ -n "$best" ] || { echo "$0: colmap mapper made no model, see $out/logs/mapper.log" >&2; exit 1; }
cp "$best"/*.bin "$out/full_model/bin/"
rm -rf "$out/sparse"
colmap model_converter --input_path "$out/full_model/bin" --output_path "$out/mapping_model/txt" \
  --output_type TXT >"$out/logs/model_converter_full.log" 2>&1

# Queries: every Nth registered photo in name order, from the offset on.
python3 - "$out" "$query_every" "$query_offset" <<'PY'
import sys
out, every, offset = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
cameras = {}
for line in open(f"{out}/mapping_model/txt/cameras.txt"):
    f = line.split()
    if f and not f[0].startswith("#"):
        cameras[f[0]] = f[1:]
lines = [l for l in open(f"{out}/mapping_model/txt/images.txt") if not l.startswith("#")]
poses = {}
for line in lines[0::2]:
    f = line.split()
    if len(f) >= 10:
        poses[f[9]] = (f[1:8], cameras[f[8]])
names = sorted(poses)
queries = names[offset::every]
with open(f"{out}/query_list.txt", "w") as q, open(f"{out}/queries_gt.txt", "w") as g, \
        open(f"{out}/queries_with_intrinsics.txt", "w") as k:
    g.write("# Ground-truth query poses from the FULL COLMAP model (same frame as mapping_model).\n"
            "# COLMAP convention: world-to-camera, X_cam = R(q) * X_world + t, q = (qw qx qy qz).\n"
            "# Camera centre C = -R^T t. Pixel coords: COLMAP convention (origin at top-left corner of top-left pixel).\n"
            "# NAME QW QX QY QZ TX TY TZ CAMERA_MODEL WIDTH HEIGHT PARAMS...\n")
    for name in queries:
        pose, camera = poses[name]
        q.write(name + "\n")
        g.write(" ".join([name] + pose + camera) + "\n")
        k.write(" ".join([name] + camera) + "\n")
print(f"  {len(names)} registered photos, {len(queries)} queries")
PY
while read -r name; do ln -sf "$photos/$name" "$out/query_images/$name"; done <"$out/query_list.txt"
run image_deleter colmap image_deleter --input_path "$out/full_model/bin" \
  --output_path "$out/mapping_model/bin" --image_names_path "$out/query_list.txt"
colmap model_converter --input_path "$out/mapping_model/bin" --output_path "$out/mapping_model/txt" \
  --output_type TXT >"$out/logs/model_converter_mapping.log" 2>&1
printf '# no metric ground truth: model units\nscale 1\n' >"$out/scale_to_metres.txt"

python3 - "$out" "$photos" "$query_every" "$query_offset" "$max_image_size" "$max_features" "$single_camera" <<'PY'
import json, sqlite3, sys
out, photos, every, offset, size, features, single = sys.argv[1:8]

def analyze(path):
    images = [l for l in open(f"{path}/images.txt") if not l.startswith("#")]
    points = [l for l in open(f"{path}/points3D.txt") if not l.startswith("#")]
    return {"registered_images": len(images) // 2, "points3D": len(points),
            "observations": sum((len(l.split()) - 8) // 2 for l in points)}

db = sqlite3.connect(f"{out}/database.db")
sizes = db.execute("SELECT min(max(width, height)), max(max(width, height)) FROM cameras").fetchone()
stats = {"images_in_database": db.execute("SELECT count(*) FROM images").fetchone()[0],
         "cameras_in_database": db.execute("SELECT count(*) FROM cameras").fetchone()[0],
         "longest_side_px": list(sizes),
         "with_exif_focal": db.execute("SELECT count(*) FROM cameras WHERE prior_focal_length = 1").fetchone()[0],
         "mapping_model": analyze(f"{out}/mapping_model/txt"),
         "queries": [l.strip() for l in open(f"{out}/query_list.txt") if l.strip()]}
json.dump(stats, open(f"{out}/stats.json", "w"), indent=1)
with open(f"{out}/README.txt", "w") as readme:
    readme.write(f"""Made by cwloc's bench/make_photo_dataset.sh from the photos in {photos}
(colmap 3.8, CPU):
  bench/make_photo_dataset.sh PHOTOS_DIR OUT_DIR --query-every {every} --query-offset {offset} \\
      --max-image-size {size} --max-features {features}{' --single-camera' if single == '1' else ''}
feature_extractor (SIMPLE_RADIAL, {'one camera' if single == '1' else 'one camera per photo'}), exhaustive_matcher,
mapper (largest model = full_model), registered photos {offset}, {offset} + {every}, ... in name order held out
(query_list.txt; queries_gt.txt = their full-model poses and cameras), image_deleter
(mapping_model = full model minus the queries). Model units, no metric scale. Times in logs/.
Stats: {json.dumps(stats)}
Research/test data: never copy it into the project.
""")
print(json.dumps(stats))
PY
