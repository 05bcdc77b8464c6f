#!/usr/bin/env bash
# COLMAP itself as the peer on real data: register the held-out queries of herz_jesu_p25 into
# its mapping model with COLMAP (pairs matching query x mapping image, then image_registrator)
# and with cwloc, both on one thread, and print one error table (cwloc-eval) and one time table.
#
#   bench/colmap_peer.sh WORKDIR [DATASET_DIR]     (default ../shared/data/herz_jesu_p25)
#   CWLOC_BIN=build-a/bin bench/colmap_peer.sh /tmp/peer
#
# Features are precomputed in the dataset's database for both tools: SIFT extraction is not
# timed for either. The dataset is never written: everything happens on a copy in WORKDIR.
set -euo pipefail
top="$(cd "$(dirname "$0")/.." && pwd)"
bin="${CWLOC_BIN:-$top/build/bin}"
[ $# -ge 1 ] || { echo "usage: $0 WORKDIR [DATASET_DIR]" >&2; exit 2; }
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
# images and 3D points where they are. The queries share camera 1, which the mapping images
# already registered, so COLMAP keeps the model's refined intrinsics fixed for them.
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

echo "## cwloc: index build (one-off), then cwloc-localize with known intrinsics (1 thread)"
timed cwloc_index_build "$bin/cwloc-index" build --model "$data/mapping_model/bin" --database "$db" \
  -o "$work/hj.cwl"
# The whole command is timed: process start, index open, reading the query features, output.
status=0
timed cwloc_localize "$bin/cwloc-localize" --index "$work/hj.cwl" --database "$db" \
  --query-list "$data/queries_with_intrinsics.txt" --threads 1 -q \
  -o "$work/cwloc.jsonl" --poses "$work/cwloc_poses.txt" || status=$?
[ "$status" -le 1 ] || exit "$status"   # 1 = some query not localized, still worth scoring

echo "## evaluation"
eval_args=(--results "$work/colmap_poses.txt" --label colmap --results "$work/cwloc.jsonl" --label cwloc
  --gt "$data/queries_gt.txt" --scale "$data/scale_to_metres.txt")
"$bin/cwloc-eval" "${eval_args[@]}"
"$bin/cwloc-eval" "${eval_args[@]}" --json >"$work/peer_eval.json"
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
