#!/usr/bin/env bash
# Photo -> features, one thread, per photo: COLMAP 3.8's CPU SIFT (colmap feature_extractor)
# against cwloc's (cwloc-sift-bench: decode + ExtractSift), medians of hyperfine runs; then the
# whole photo -> pose command (cwloc-localize --image) against an index of the photos' dataset
# (PHOTO_DIR/../mapping_model/bin and PHOTO_DIR/../database.db), also on one thread.
#
#   bench/extraction_benchmark.sh [BUILD_DIR] [PHOTO_DIR] [RUNS]
#   defaults: build, ../shared/data/herz_jesu_p25/query_images, 3
#
# Both sides run as one process per photo (startup included). COLMAP gets the settings the
# dataset's database was made with; ours the same options (max_num_features 6000).
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-$here/build}"
photos="${2:-$here/../shared/data/herz_jesu_p25/query_images}"
runs="${3:-3}"
bin="$build/bin"
for tool in colmap hyperfine jq; do
  command -v "$tool" >/dev/null || { echo "extraction_benchmark: $tool not found" >&2; exit 2; }
done
[ -x "$bin/cwloc-sift-bench" ] || { echo "extraction_benchmark: build cwloc_sift_bench first" >&2; exit 2; }

tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
export QT_QPA_PLATFORM=offscreen
export OMP_NUM_THREADS=1

median_ms() { jq -r '.results[0].median * 1000 | floor' "$1"; }

data="$(cd "$photos/.." && pwd)"
"$bin/cwloc-index" build --model "$data/mapping_model/bin" --database "$data/database.db" \
  -o "$tmp/index.cwl" >/dev/null

printf '| photo | COLMAP feature_extractor ms | cwloc-sift-bench ms | ratio | cwloc in-process decode+extract ms | cwloc-localize --image (photo -> pose) ms |\n'
printf '|---|---|---|---|---|---|\n'
for photo in "$photos"/*.jpg; do
  name="$(basename "$photo")"
  echo "$name" > "$tmp/list.txt"
  hyperfine --runs "$runs" --warmup 0 --style none --export-json "$tmp/colmap.json" \
    --prepare "rm -f $tmp/db.db" \
    "colmap feature_extractor --database_path $tmp/db.db --image_path $photos \
       --image_list_path $tmp/list.txt \
       --ImageReader.single_camera 1 --ImageReader.camera_model SIMPLE_RADIAL \
       --SiftExtraction.use_gpu 0 --SiftExtraction.num_threads 1 \
       --SiftExtraction.max_image_size 1600 --SiftExtraction.max_num_features 6000" \
    >/dev/null 2>&1
  hyperfine --runs "$runs" --warmup 1 --style none --export-json "$tmp/cwloc.json" \
    "$bin/cwloc-sift-bench --max-num-features 6000 $photo" >/dev/null 2>&1
  inproc="$("$bin/cwloc-sift-bench" --max-num-features 6000 --repeat "$runs" "$photo" | awk 'NR==2 {print $5}')"
  colmap_ms="$(median_ms "$tmp/colmap.json")"
  cwloc_ms="$(median_ms "$tmp/cwloc.json")"
  hyperfine --runs "$runs" --warmup 1 --style none --export-json "$tmp/pose.json" \
    "$bin/cwloc-localize --index $tmp/index.cwl --image $photo --max-image-size 1600 \
       --max-features 6000 --threads 1 -q -o $tmp/pose.jsonl" >/dev/null 2>&1
  pose_ms="$(median_ms "$tmp/pose.json")"
  ratio="$(awk -v a="$colmap_ms" -v b="$cwloc_ms" 'BEGIN {printf "%.2f", a / b}')"
  printf '| %s | %s | %s | %s | %s | %s |\n' "$name" "$colmap_ms" "$cwloc_ms" "$ratio" "$inproc" \
    "$pose_ms"
done
