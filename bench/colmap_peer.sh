#!/usr/bin/env bash
# COLMAP itself as the peer on real data: register the held-out queries of a data set into its
# mapping model with COLMAP (pairs matching query x mapping image, then image_registrator) and
# with cwloc, both on one thread, and print one error table (cwloc-eval), one per-query table
# (errors and the focal lengths used) and one time table.
#
#   bench/colmap_peer.sh [--unknown-focal | --focal-prior] WORKDIR [DATASET_DIR]
#       (DATASET_DIR defaults to ../shared/data/herz_jesu_p25)
#   CWLOC_BIN=build-a/bin bench/colmap_peer.sh /tmp/peer
#
# Modes (the intrinsics both tools get for the queries):
#   default          the model's refined camera, known: COLMAP shares the mapping images' camera,
#                    cwloc reads queries_with_intrinsics.txt;
#   --unknown-focal  each query gets its own database camera holding the feature extractor's
#                    guess f = 1.2 * max(w, h), k = 0, with prior_focal_length = 0: COLMAP's
#                    image_registrator estimates the focal length (focal sampling with P3P) and
#                    refines it with k; cwloc reads the same camera from the database
#                    (calibration "unknown");
#   --focal-prior    the same with the database camera's focal length (EXIF where the data set
#                    has it) and prior_focal_length = 1: COLMAP runs P3P with the prior, then
#                    refines f and k; cwloc reads a focal prior (calibration "focal-prior").
#
# Features are precomputed in the dataset's database for both tools: SIFT extraction is not
# timed for either. The dataset is never written: everything happens on a copy in WORKDIR.
set -euo pipefail
top="$(cd "$(dirname "$0")/.." && pwd)"
bin="${CWLOC_BIN:-$top/build/bin}"
mode=known
case "${1:-}" in
  --unknown-focal) mode=unknown-focal; shift ;;
  --focal-prior) mode=focal-prior; shift ;;
  -*) echo "$0: unknown option $1" >&2; exit 2 ;;
esac
[ $# -ge 1 ] || { echo "usage: $0 [--unknown-focal | --focal-prior] WORKDIR [DATASET_DIR]" >&2; exit 2; }
data="$(realpath -m "${2:-$top/../shared/data/herz_jesu_p25}")"
for f in database.db mapping_model/bin query_list.txt queries_with_intrinsics.txt queries_gt.txt scale_to_metres.txt; do
  [ -e "$data/$f" ] || { echo "$0: $data/$f is missing" >&2; exit 2; }
done
work="$(realpath -m "$1")"
case "$work/" in "$data"/*) echo "$0: WORKDIR $work is inside the dataset $data" >&2; exit 2 ;; esac
mkdir -p "$work/logs"
export QT_QPA_PLATFORM=offscreen   # colmap is a Qt program; no X server here
db="$work/peer.db"
nq="$(grep -c . "$data/query_list.txt")"
echo "## mode: $mode, data set: $data"

# timed NAME CMD...: runs CMD with its output in logs/NAME.log, wall seconds in $secs[NAME].
declare -A secs
timed() {
  local name="$1" t0 t1 status=0
  shift
  t0="$(date +%s.%N)"
  "$@" >"$work/logs/$name.log" 2>&1 || status=$?
  t1="$(date +%s.%N)"
  secs[$name]="$(awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.3f", b - a }')"
  echo "  $name: ${secs[$name]} s (exit $status)"
  return "$status"
}

echo "## copying the database; dropping every stored match that involves a query"
install -m 644 "$data/database.db" "$db"   # the dataset's files are read-only
qnames="$(sed "/^$/d; s/.*/'&'/" "$data/query_list.txt" | paste -sd,)"
qids="SELECT image_id FROM images WHERE name IN ($qnames)"
# pair_id = image_id1 * 2147483647 + image_id2 with image_id1 < image_id2 < 2147483647.
for table in matches two_view_geometries; do
  sqlite3 "$db" "DELETE FROM $table WHERE pair_id / 2147483647 IN ($qids) OR pair_id % 2147483647 IN ($qids);"
done
sqlite3 "$db" "SELECT 'images ' || (SELECT count(*) FROM images) || ', queries ' || (SELECT count(*) FROM ($qids))
  || ', matches left ' || (SELECT count(*) FROM matches) || ', two_view_geometries left ' || (SELECT count(*) FROM two_view_geometries);"

if [ "$mode" != known ]; then
  echo "## giving each query its own camera ($mode)"
  python3 - "$db" "$data/query_list.txt" "$mode" <<'PY'
import sqlite3, struct, sys
db_path, list_path, mode = sys.argv[1:4]
names = [line.split()[0] for line in open(list_path) if line.strip()]
db = sqlite3.connect(db_path)
for name in names:
    camera_id, = db.execute("SELECT camera_id FROM images WHERE name = ?", (name,)).fetchone()
    model, width, height, params = db.execute(
        "SELECT model, width, height, params FROM cameras WHERE camera_id = ?", (camera_id,)).fetchone()
    assert model == 2, f"{name}: the database camera is model {model}, expected SIMPLE_RADIAL (2)"
    focal = struct.unpack("<4d", params)[0]
    if mode == "unknown-focal":
        focal, prior = 1.2 * max(width, height), 0   # COLMAP's extractor guess without EXIF
    else:
        prior = 1
    blob = struct.pack("<4d", focal, width / 2, height / 2, 0.0)
    cursor = db.execute("INSERT INTO cameras (model, width, height, params, prior_focal_length) "
                        "VALUES (2, ?, ?, ?, ?)", (width, height, blob, prior))
    db.execute("UPDATE images SET camera_id = ? WHERE name = ?", (cursor.lastrowid, name))
    print(f"  {name}: camera {cursor.lastrowid} SIMPLE_RADIAL {width} {height} f={focal:.2f} k=0, prior_focal_length={prior}")
db.commit()
PY
fi

echo "## COLMAP: matching each query with each mapping image, then image_registrator (1 thread)"
sqlite3 "$db" "SELECT name FROM images WHERE image_id NOT IN ($qids) ORDER BY name;" >"$work/mapping_names.txt"
grep -v '^$' "$data/query_list.txt" | while read -r q; do
  sed "s/^/$q /" "$work/mapping_names.txt"
done >"$work/pairs.txt"
echo "  $(wc -l <"$work/pairs.txt") pairs"
timed colmap_matching colmap matches_importer --database_path "$db" --match_type pairs \
  --match_list_path "$work/pairs.txt" --SiftMatching.use_gpu 0 --SiftMatching.num_threads 1
# image_registrator only adds the model's unregistered database images (the queries) by
# absolute pose RANSAC + pose refinement; it runs no bundle adjustment and leaves the mapping
# images and 3D points where they are. In the default mode the queries share camera 1, which the
# mapping images already registered, so COLMAP keeps the model's refined intrinsics fixed for
# them; in the other modes each query's camera is fresh, so COLMAP estimates (or starts from the
# prior) and refines its focal length and k (IncrementalMapper::RegisterNextImage).
rm -rf "$work/colmap_registered" "$work/colmap_registered_txt"
mkdir -p "$work/colmap_registered" "$work/colmap_registered_txt"
timed colmap_registration colmap image_registrator --database_path "$db" \
  --input_path "$data/mapping_model/bin" --output_path "$work/colmap_registered" --Mapper.num_threads 1
colmap model_converter --input_path "$work/colmap_registered" \
  --output_path "$work/colmap_registered_txt" --output_type TXT >"$work/logs/model_converter.log" 2>&1
# images.txt: after the # comments, a pose line (ID QW QX QY QZ TX TY TZ CAMERA_ID NAME) then a
# points line per image; keep the pose lines of the queries.
awk 'NR == FNR { query[$1] = 1; next }
     /^#/ { next }
     { n++ } n % 2 == 1 && ($10 in query) { print $10, $2, $3, $4, $5, $6, $7, $8 }' \
  "$data/query_list.txt" "$work/colmap_registered_txt/images.txt" | sort >"$work/colmap_poses.txt"

query_list="$data/queries_with_intrinsics.txt"   # known: the model's camera on each line
[ "$mode" = known ] || query_list="$data/query_list.txt"   # else the database's query cameras
echo "## cwloc: index build (one-off), then cwloc-localize, $mode intrinsics (1 thread)"
timed cwloc_index_build "$bin/cwloc-index" build --model "$data/mapping_model/bin" --database "$db" \
  -o "$work/hj.cwl"
# The whole command is timed: process start, index open, reading the query features, output.
status=0
timed cwloc_localize "$bin/cwloc-localize" --index "$work/hj.cwl" --database "$db" \
  --query-list "$query_list" --threads 1 -q \
  -o "$work/cwloc.jsonl" --poses "$work/cwloc_poses.txt" || status=$?
[ "$status" -le 1 ] || exit "$status"   # 1 = some query not localized, still worth scoring

echo "## evaluation"
eval_args=(--results "$work/colmap_poses.txt" --label colmap --results "$work/cwloc.jsonl" --label cwloc
  --gt "$data/queries_gt.txt" --scale "$data/scale_to_metres.txt")
"$bin/cwloc-eval" "${eval_args[@]}"
"$bin/cwloc-eval" "${eval_args[@]}" --json >"$work/peer_eval.json"
echo
# Per query: both tools' errors and the camera each used (COLMAP's from the registered model).
python3 - "$data/queries_gt.txt" "$data/scale_to_metres.txt" "$work/colmap_registered_txt" \
  "$work/cwloc.jsonl" "$data/queries_with_intrinsics.txt" <<'PY'
import json, math, sys
gt_path, scale_path, colmap_dir, cwloc_path, intrinsics_path = sys.argv[1:6]

def quat_to_matrix(w, x, y, z):
    return [[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]]

def center(q, t):
    r = quat_to_matrix(*q)
    return [-sum(r[j][i] * t[j] for j in range(3)) for i in range(3)]

def errors(q, t, q_gt, t_gt, scale):
    c, c_gt = center(q, t), center(q_gt, t_gt)
    position = scale * math.dist(c, c_gt)
    n = math.sqrt(sum(v * v for v in q)) * math.sqrt(sum(v * v for v in q_gt))
    dot = abs(sum(a * b for a, b in zip(q, q_gt))) / n
    return position, math.degrees(2 * math.acos(min(1.0, dot)))

scale = 1.0
for line in open(scale_path):
    if line.startswith("scale"): scale = float(line.split()[1])
unit = "m" if scale != 1.0 else "units"
gt = {}
for line in open(gt_path):
    f = line.split()
    if f and not f[0].startswith("#"):
        gt[f[0]] = ([float(v) for v in f[1:5]], [float(v) for v in f[5:8]])
model = {}
for line in open(intrinsics_path):
    f = line.split()
    if f: model[f[0]] = [float(v) for v in f[4:]]
cameras = {}
for line in open(f"{colmap_dir}/cameras.txt"):
    f = line.split()
    if f and not f[0].startswith("#"): cameras[f[0]] = [float(v) for v in f[4:]]
colmap = {}
lines = [l for l in open(f"{colmap_dir}/images.txt") if not l.startswith("#")]
for line in lines[0::2]:
    f = line.split()
    if len(f) >= 10 and f[9] in gt:
        colmap[f[9]] = ([float(v) for v in f[1:5]], [float(v) for v in f[5:8]], cameras[f[8]])
cwloc = {}
for line in open(cwloc_path):
    if not line.strip(): continue
    r = json.loads(line)
    if r.get("success"):
        cwloc[r["name"]] = (r["pose"]["qvec"], r["pose"]["tvec"], r["camera"]["params"])

def cell(entry, name):
    if entry is None: return f"{'not localized':>40}"
    q, t, params = entry
    p, r = errors(q, t, *gt[name], scale)
    k = params[3] if len(params) > 3 else 0.0
    return f"{p:>10.4f} {r:>7.4f} {params[0]:>9.2f} {k:>8.4f}"

print(f"per query: position error ({unit}), rotation error (deg), focal (px) and k used;"
      " the model's refined camera for reference")
head = f"{'pos':>10} {'rot':>7} {'focal':>9} {'k':>8}"
print(f"{'query':<14} | {'colmap':^37} | {'cwloc':^37} | model focal, k")
print(f"{'':<14} | {head} | {head} |")
for name in sorted(gt):
    ref = model.get(name, [float("nan")] * 4)
    print(f"{name:<14} | {cell(colmap.get(name), name)} | {cell(cwloc.get(name), name)} |"
          f" {ref[0]:.2f}, {ref[3] if len(ref) > 3 else 0.0:.4f}")
PY
echo
# Time table: COLMAP's time is matching + registration, cwloc's the whole cwloc-localize command.
awk -v nq="$nq" -v cm="${secs[colmap_matching]}" -v cr="${secs[colmap_registration]}" \
  -v cl="${secs[cwloc_localize]}" -v cb="${secs[cwloc_index_build]}" \
  -v ncol="$(wc -l <"$work/colmap_poses.txt")" -v ncw="$(wc -l <"$work/cwloc_poses.txt")" 'BEGIN {
  printf "%-7s %-10s %-10s %-10s %s\n", "tool", "localized", "wall s", "s / query", "what is timed"
  printf "%-7s %-10s %-10.3f %-10.3f matches_importer %.3f s + image_registrator %.3f s\n", "colmap", ncol "/" nq, cm + cr, (cm + cr) / nq, cm, cr
  printf "%-7s %-10s %-10.3f %-10.3f the whole cwloc-localize command (index open included)\n", "cwloc", ncw "/" nq, cl, cl / nq
  printf "one-off: cwloc-index build %.3f s. Feature extraction is excluded for both tools.\n", cb
}'
"$bin/cwloc-plot" errors --report "$work/peer_eval.json" \
  --title "$(basename "$data"): COLMAP and cwloc against ground truth" -o "$work/peer_errors.png"
