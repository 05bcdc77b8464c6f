#!/usr/bin/env bash
# The aarch64 device build, under qemu-user, must return what x86-64 returns from the same
# index built on x86-64: the same localized set, the same inlier and correspondence counts,
# poses and cameras within 1e-6 relative (tools/compare_results.py). Both run the refiner a
# device build has (--refiner builtin), so the x86-64 side is the full build's cwloc-localize.
# Data: herz_jesu_p25 from its photos and from its stored query features, and a generated city
# from its query features; both also with a compact index (format 1.2, --compact).
#
# Usage: tools/check_arm64.sh NATIVE_BUILD ARM64_DEVICE_BUILD
#   NATIVE_BUILD: a full build (cwloc-index, cwloc-synth) that makes the indexes.
set -euo pipefail
[ $# -eq 2 ] || { echo "usage: tools/check_arm64.sh NATIVE_BUILD ARM64_DEVICE_BUILD" >&2; exit 2; }
native=$(realpath "$1")
arm=$(realpath "$2")
cd "$(dirname "$0")/.."
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# Runs both builds on one query set and compares, in the background, as many sets at once as
# there are cores (qemu runs one thread); $1 names the set, the rest are the options.
# finish_compares prints each set's outcome in order and fails if one failed.
sets=()
compare() {
  local name=$1
  shift
  while [ "$(jobs -rp | wc -l)" -ge "$(nproc)" ]; do wait -n || true; done
  sets+=("$name")
  {
    if (
      status=0
      "$native/bin/cwloc-localize" "$@" --refiner builtin -q -o "$work/$name.x86.jsonl" || status=$?
      [ "$status" -le 1 ] || { echo "check_arm64: x86-64 failed on $name ($status)"; exit 1; }
      status=0
      qemu-aarch64 "$arm/bin/cwloc-localize" "$@" --refiner builtin -q -o "$work/$name.arm64.jsonl" || status=$?
      [ "$status" -le 1 ] || { echo "check_arm64: aarch64 failed on $name ($status)"; exit 1; }
      echo -n "check_arm64: $name: "
      python3 tools/compare_results.py "$work/$name.x86.jsonl" "$work/$name.arm64.jsonl"
    ) >"$work/$name.out" 2>&1; then echo ok; else echo failed; fi >"$work/$name.status"
  } &
}
finish_compares() {
  wait
  local failed=0
  for name in "${sets[@]}"; do
    cat "$work/$name.out"
    [ "$(cat "$work/$name.status")" = ok ] || failed=1
  done
  return "$failed"
}

# Writes a feature-file query list (NAME.txt MODEL W H PARAMS) for the queries of a data set.
feature_queries() {
  local database=$1 intrinsics=$2 out=$3
  mkdir -p "$out"
  # shellcheck disable=SC2046
  python3 tests/data/export_query_features.py "$database" "$out" $(awk '!/^#/ && NF { print $1 }' "$intrinsics")
  awk '!/^#/ && NF { $1 = $1 ".txt"; print }' "$intrinsics" >"$out/list.txt"
}

data=../shared/data/herz_jesu_p25
if [ -d "$data" ]; then
  "$native/bin/cwloc-index" build --model "$data/mapping_model/bin" --database "$data/database.db" \
    -o "$work/herz_jesu.cwl" >/dev/null 2>&1
  feature_queries "$data/database.db" "$data/queries_with_intrinsics.txt" "$work/herz_features"
  compare herz_jesu_features --index "$work/herz_jesu.cwl" --query-list "$work/herz_features/list.txt"
  # Three of the five photos at 800 pixels: the same SIFT kernels as all five at the database's
  # 1600, in a sixth of qemu's time.
  head -3 "$data/query_list.txt" >"$work/herz_photos.txt"
  compare herz_jesu_photos --index "$work/herz_jesu.cwl" --image-list "$work/herz_photos.txt" \
    --image-dir "$data/query_images" --max-image-size 800 --max-features 6000 --threads "$(nproc)"
  "$native/bin/cwloc-index" build --model "$data/mapping_model/bin" --database "$data/database.db" \
    --compact -o "$work/herz_jesu_compact.cwl" >/dev/null 2>&1
  compare herz_jesu_compact --index "$work/herz_jesu_compact.cwl" \
    --query-list "$work/herz_features/list.txt"
else
  echo "check_arm64: ../shared/data/herz_jesu_p25 not found; generated city only" >&2
fi

"$native/bin/cwloc-synth" --preset demo --seed 7 -o "$work/city" >/dev/null
"$native/bin/cwloc-index" build --model "$work/city/mapping_model/bin" \
  --database "$work/city/database.db" -o "$work/city.cwl" >/dev/null 2>&1
feature_queries "$work/city/database.db" "$work/city/queries_with_intrinsics.txt" "$work/city_features"
compare city_features --index "$work/city.cwl" --query-list "$work/city_features/list.txt"
"$native/bin/cwloc-index" build --model "$work/city/mapping_model/bin" \
  --database "$work/city/database.db" --compact -o "$work/city_compact.cwl" >/dev/null 2>&1
compare city_compact --index "$work/city_compact.cwl" --query-list "$work/city_features/list.txt"
finish_compares
