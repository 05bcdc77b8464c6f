#!/usr/bin/env bash
# Photo -> features -> pose, per photo, in one run (docs/sift.md, "Speed"):
#  - COLMAP 3.8's CPU SIFT (colmap feature_extractor, one thread, the dataset's settings:
#    max_image_size 1600, max_num_features 6000), one process per run (hyperfine median);
#  - OpenCV's SIFT (Debian's python3-opencv, one thread) at its defaults and at COLMAP's
#    thresholds, in process (bench/opencv_sift_time.py: decode + detectAndCompute, median);
#  - ours (cwloc-sift-bench: decode + ExtractSift, in process, median) at 6000 features and at
#    the defaults (8192), on one thread and on two;
#  - photo -> pose (cwloc-localize --image, one process, hyperfine median) at 6000 features and
#    at the defaults, with its peak RSS (median of the runs), and in the fast mode
#    (--first-octave 0, and 1) at 6000 features.
#
#   bench/extraction_benchmark.sh [BUILD_DIR] [PHOTO_DIR] [RUNS]
#   defaults: build, ../shared/data/herz_jesu_p25/query_images, 3
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
opencv=1
/usr/bin/python3 -c 'import cv2' 2>/dev/null || {
  opencv=0
  echo "extraction_benchmark: no OpenCV column (apt-get install python3-opencv)" >&2
}

tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
export QT_QPA_PLATFORM=offscreen
export OMP_NUM_THREADS=1

median_ms() { jq -r '.results[0].median * 1000 | floor' "$1"; }
sift_ms() {  # FEATURES THREADS PHOTO: in-process median of decode + extract
  "$bin/cwloc-sift-bench" --max-num-features "$1" --threads "$2" --repeat "$runs" "$3" |
    awk 'NR==2 {printf "%.0f", $5}'
}
pose() {  # PHOTO MAX_IMAGE_SIZE MAX_FEATURES [FLAGS]: "median_ms peak_MB" of the whole command
  local command="$bin/cwloc-localize --index $tmp/index.cwl --image $1 --max-image-size $2 \
    --max-features $3 ${4:-} --threads 1 -q -o $tmp/pose.jsonl"
  hyperfine --runs "$runs" --warmup 1 --style none --export-json "$tmp/pose.json" "$command" \
    >/dev/null 2>&1
  local peaks=()
  for ((r = 0; r < runs; r++)); do
    peaks+=("$(/usr/bin/time -f %M $command 2>&1 >/dev/null | tail -1)")
  done
  printf '%s %s\n' "$(median_ms "$tmp/pose.json")" \
    "$(printf '%s\n' "${peaks[@]}" | sort -n | awk '{a[NR]=$1} END {printf "%.0f", a[int((NR+1)/2)]/1024}')"
}

data="$(cd "$photos/.." && pwd)"
"$bin/cwloc-index" build --model "$data/mapping_model/bin" --database "$data/database.db" \
  -o "$tmp/index.cwl" >/dev/null

printf '| photo | COLMAP SIFT ms (6000) | OpenCV SIFT ms (features), defaults / COLMAP thresholds | ours 1 thread ms, 6000 / 8192 | ours 2 threads ms, 6000 / 8192 | 2 threads speedup | photo -> pose ms, 6000 / defaults | peak MB, 6000 / defaults | fast photo -> pose ms, first octave 0 / 1 |\n'
printf '|---|---|---|---|---|---|---|---|---|\n'
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
  opencv_cell="-"
  if [ "$opencv" = 1 ]; then
    read -r cv_ms cv_features < <("$here/bench/opencv_sift_time.py" "$photo" "$runs" 0.04)
    read -r cv2_ms cv2_features < <("$here/bench/opencv_sift_time.py" "$photo" "$runs" 0.02)
    opencv_cell="$cv_ms ($cv_features) / $cv2_ms ($cv2_features)"
  fi
  one_6000="$(sift_ms 6000 1 "$photo")"
  one_8192="$(sift_ms 8192 1 "$photo")"
  two_6000="$(sift_ms 6000 2 "$photo")"
  two_8192="$(sift_ms 8192 2 "$photo")"
  read -r pose_6000 peak_6000 < <(pose "$photo" 1600 6000)
  read -r pose_default peak_default < <(pose "$photo" 3200 8192)
  read -r pose_fast0 _ < <(pose "$photo" 1600 6000 "--first-octave 0")
  read -r pose_fast1 _ < <(pose "$photo" 1600 6000 "--first-octave 1")
  speedup="$(awk -v a="$one_8192" -v b="$two_8192" 'BEGIN {printf "%.2f", a / b}')"
  printf '| %s | %s | %s | %s / %s | %s / %s | %s | %s / %s | %s / %s | %s / %s |\n' "$name" \
    "$(median_ms "$tmp/colmap.json")" "$opencv_cell" "$one_6000" "$one_8192" "$two_6000" \
    "$two_8192" "$speedup" "$pose_6000" "$pose_default" "$peak_6000" "$peak_default" \
    "$pose_fast0" "$pose_fast1"
done
