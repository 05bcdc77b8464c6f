#!/usr/bin/env bash
# Index updates (docs/benchmarks.md, "Updates"): correctness on real models grown by COLMAP, and
# time, memory and delta size on a generated city grown by 1 % and 10 %.
#
#   bench/update_benchmark.sh WORKDIR [--sets herz_jesu_p25,sceaux_castle,fox_video]
#                             [--held 0.25] [--seeds 5] [--city DIR [--compact]]
#
# Real sets (../shared/data/NAME): the database without the queries; the mapping model without
# its last --held share of images (colmap image_deleter) is the old model, from which `colmap
# image_registrator` and `colmap point_triangulator --clear_points 0` grow it back (new images
# registered with the old poses fixed, new points triangulated). Then the old model's index is
# updated to the grown model (with its delta), the grown model is indexed afresh, the delta
# applied to the old index, and the queries localized from their database features with both
# indexes and --seed 1..--seeds: localized queries and median position error per index.
# --city DIR (a cwloc-synth output, e.g. --views 10000000): the model without its last 1 % and
# 10 % of images (by id: whole blocks, like a new district) indexed, updated to the whole city
# and the whole city indexed, each under /usr/bin/time, in one run; --compact: compact indexes
# (cwloc-index build --compact), in WORKDIR/city_compact.
# Binaries come from $CWLOC_BIN (default: build/bin of this checkout); colmap from PATH.
set -euo pipefail
top="$(cd "$(dirname "$0")/.." && pwd)"
bin="${CWLOC_BIN:-$top/build/bin}"
me="update_benchmark.sh"
die() { echo "$me: error: $*" >&2; exit 1; }
usage() {
  echo "usage: $me WORKDIR [--sets A,B] [--held 0.25] [--seeds 5] [--city DIR [--compact]]" >&2
  exit 2
}
[ $# -ge 1 ] || usage
work="$1"
shift
sets="herz_jesu_p25,sceaux_castle,fox_video"
held=0.25
seeds=5
city=""
compact=()
while [ $# -gt 0 ]; do
  case "$1" in
    --sets) [ $# -ge 2 ] || usage; sets="$2"; shift 2 ;;
    --held) [ $# -ge 2 ] || usage; held="$2"; shift 2 ;;
    --seeds) [ $# -ge 2 ] || usage; seeds="$2"; shift 2 ;;
    --city) [ $# -ge 2 ] || usage; city="$2"; shift 2 ;;
    --compact) compact=(--compact); shift ;;
    *) usage ;;
  esac
done
for tool in cwloc-index cwloc-localize cwloc-eval; do
  [ -x "$bin/$tool" ] || die "$bin/$tool not found (build first, or set CWLOC_BIN)"
done
command -v colmap >/dev/null || die "colmap not found (Debian: apt-get install colmap)"
[ -x /usr/bin/time ] || die "/usr/bin/time not found (Debian: apt-get install time)"
mkdir -p "$work"
work="$(cd "$work" && pwd)"
data_root="$top/../shared/data"

# timed NAME COMMAND...: runs COMMAND with its wall time and peak RSS in $out/NAME.time. The
# output (the argument after -o) is removed first: replacing a GB file frees its blocks, half a
# second on this VM's disk, which is not the command's work.
timed() {
  local name="$1"
  shift
  local previous=""
  for arg in "$@"; do
    [ "$previous" = "-o" ] && rm -f "$arg"
    previous="$arg"
  done
  /usr/bin/time -f "%e %M" -o "$out/$name.time" "$@" >"$out/$name.log" 2>&1 ||
    { tail -n 5 "$out/$name.log" >&2; die "$name failed: $*"; }
}

IFS=, read -r -a set_names <<<"$sets"
for name in "${set_names[@]}"; do
  data="$data_root/$name"
  [ -d "$data" ] || die "$data not found"
  out="$work/$name"
  rm -rf "$out"
  mkdir -p "$out/old" "$out/registered" "$out/grown"
  echo "## $name" >&2
  # The database without the queries: image_registrator must not register them into the map.
  cp "$data/database.db" "$out/database.db"
  queries=$(while read -r q; do
    sqlite3 "$out/database.db" "select image_id from images where name='$q'"
  done <"$data/query_list.txt" | paste -sd, -)
  sqlite3 "$out/database.db" "
    delete from matches where pair_id / 2147483647 in ($queries) or pair_id % 2147483647 in ($queries);
    delete from two_view_geometries where pair_id / 2147483647 in ($queries) or pair_id % 2147483647 in ($queries);
    delete from keypoints where image_id in ($queries); delete from descriptors where image_id in ($queries);
    delete from images where image_id in ($queries);"
  if [ "$(sqlite3 "$out/database.db" 'select count(*) from two_view_geometries')" = 0 ]; then
    # A database shipped without its matches (fox_video): match as the set's README did.
    colmap exhaustive_matcher --database_path "$out/database.db" --SiftMatching.use_gpu 0 \
      --SiftMatching.num_threads 2 >"$out/exhaustive_matcher.log" 2>&1
  fi
  mkdir -p "$out/mapping_txt"
  colmap model_converter --input_path "$data/mapping_model/bin" --output_path "$out/mapping_txt" \
    --output_type TXT >/dev/null 2>&1
  grep -v '^#' "$out/mapping_txt/images.txt" | awk 'NR % 2 == 1 {print $1, $10}' | sort -n >"$out/images.txt"
  total=$(wc -l <"$out/images.txt")
  keep=$(python3 -c "import math; print(max(2, round($total * (1 - $held))))")
  tail -n +"$((keep + 1))" "$out/images.txt" | awk '{print $2}' >"$out/held_out.txt"
  colmap image_deleter --input_path "$data/mapping_model/bin" --output_path "$out/old" \
    --image_names_path "$out/held_out.txt" >"$out/image_deleter.log" 2>&1
  colmap image_registrator --database_path "$out/database.db" --input_path "$out/old" \
    --output_path "$out/registered" >"$out/image_registrator.log" 2>&1
  colmap point_triangulator --database_path "$out/database.db" --image_path "$out" \
    --input_path "$out/registered" --output_path "$out/grown" --clear_points 0 \
    >"$out/point_triangulator.log" 2>&1
  timed build_old "$bin/cwloc-index" build --model "$out/old" --database "$out/database.db" -o "$out/old.cwl"
  timed update "$bin/cwloc-index" update --index "$out/old.cwl" --model "$out/grown" \
    --database "$out/database.db" -o "$out/updated.cwl" --delta "$out/grown.cwld" --json
  timed build_grown "$bin/cwloc-index" build --model "$out/grown" --database "$out/database.db" -o "$out/full.cwl"
  timed apply "$bin/cwloc-index" apply --index "$out/old.cwl" --delta "$out/grown.cwld" -o "$out/applied.cwl"
  cmp -s "$out/applied.cwl" "$out/updated.cwl" || die "$name: apply did not give the update's bytes"
  for index in updated full; do
    "$bin/cwloc-index" info --json "$out/$index.cwl" >"$out/$index.info.json"
    for ((seed = 1; seed <= seeds; seed++)); do
      status=0
      "$bin/cwloc-localize" --index "$out/$index.cwl" --database "$data/database.db" \
        --query-list "$data/queries_with_intrinsics.txt" --seed "$seed" --threads 1 -q \
        -o "$out/$index.seed$seed.jsonl" || status=$?
      [ "$status" -le 1 ] || die "$name: cwloc-localize failed ($index, seed $seed)"
      "$bin/cwloc-eval" --results "$out/$index.seed$seed.jsonl" --gt "$data/queries_gt.txt" \
        --scale "$data/scale_to_metres.txt" --json >"$out/$index.seed$seed.eval.json"
    done
  done
done

city_out="$work/city${compact:+_compact}"
if [ -n "$city" ]; then
  out="$city_out"
  mkdir -p "$out"
  model="$city/mapping_model/bin"
  colmap model_analyzer --path "$model" >"$out/model.txt" 2>&1
  # Model image ids ascend with the blocks; the last ones are whole blocks.
  python3 - "$model/images.bin" "$out" <<'PY'
import struct, sys
with open(sys.argv[1], "rb") as f:
    (count,) = struct.unpack("<Q", f.read(8))
    ids = []
    for _ in range(count):
        (image_id,) = struct.unpack("<I", f.read(4))
        f.read(8 * 7 + 4)
        while f.read(1) != b"\0":
            pass
        (points,) = struct.unpack("<Q", f.read(8))
        f.seek(points * 24, 1)
        ids.append(image_id)
ids.sort()
for percent in (1, 10):
    k = round(len(ids) * percent / 100)
    open(f"{sys.argv[2]}/held_{percent}.txt", "w").write("".join(f"{i}\n" for i in ids[-k:]))
PY
  for percent in 1 10; do
    if [ ! -f "$out/old_$percent/images.bin" ]; then
      mkdir -p "$out/old_$percent"
      colmap image_deleter --input_path "$model" --output_path "$out/old_$percent" \
        --image_ids_path "$out/held_$percent.txt" >"$out/image_deleter_$percent.log" 2>&1
    fi
    [ -f "$out/old_$percent.cwl" ] || timed "build_old_$percent" "$bin/cwloc-index" build \
      "${compact[@]}" --model "$out/old_$percent" --database "$city/database.db" \
      -o "$out/old_$percent.cwl"
  done
  timed build_full "$bin/cwloc-index" build "${compact[@]}" --model "$model" \
    --database "$city/database.db" -o "$out/full.cwl"
  for percent in 1 10; do
    timed "update_$percent" "$bin/cwloc-index" update --index "$out/old_$percent.cwl" --model "$model" \
      --database "$city/database.db" -o "$out/updated_$percent.cwl" --delta "$out/grown_$percent.cwld" --json
    timed "apply_$percent" "$bin/cwloc-index" apply --index "$out/old_$percent.cwl" \
      --delta "$out/grown_$percent.cwld" -o "$out/applied_$percent.cwl"
    cmp -s "$out/applied_$percent.cwl" "$out/updated_$percent.cwl" ||
      die "city $percent %: apply did not give the update's bytes"
    rm -f "$out/applied_$percent.cwl"
  done
fi

python3 - "$work" "$sets" "$seeds" "$city" "$city_out" <<'PY'
import json, os, statistics, sys
work, seeds, city, city_out = sys.argv[1], int(sys.argv[3]), sys.argv[4], sys.argv[5]
sets = [name for name in sys.argv[2].split(",") if name]
def time_of(path):
    seconds, kb = open(path).read().split()
    return float(seconds), int(kb) / 1024
def checksums(path):
    return {s["tag"]: s["checksum"] for s in json.load(open(path))["sections"]}
if sets:
    print("| set | images old -> grown | views added | kd-forest | delta (% of index) | sections equal to the full build's | v_NN equal | localized updated / full (all seeds) | median position error updated / full (m) | ratio |")
    print("|---|---|---|---|---|---|---|---|---|---|")
for name in sets:
    out = os.path.join(work, name)
    report = json.load(open(f"{out}/update.log"))
    a, b = checksums(f"{out}/updated.info.json"), checksums(f"{out}/full.info.json")
    # The manifest and the covariance calibration (the last full build's) are the update's own;
    # the kd-forest too, unless the update rebuilt it.
    shared = [t for t in b if t not in ("MANI", "PCAL", "KDND", "KDRT", "KDLF")]
    equal = sum(a.get(t) == b[t] for t in shared)
    localized, medians = {}, {}
    for index in ("updated", "full"):
        runs = [json.load(open(f"{out}/{index}.seed{s}.eval.json"))["runs"][0] for s in range(1, seeds + 1)]
        localized[index] = sum(r["localized"] for r in runs)
        errors = [q["position_error"] for r in runs for q in r["per_query"] if q.get("position_error") is not None]
        medians[index] = statistics.median(errors) if errors else float("nan")
    changes = report["changes"]
    images = report["counts"]["images"]
    print(f"| {name} | {images - changes['images_added']} -> {images} | {changes['views_added']} | "
          f"{'rebuilt' if changes['forest_rebuilt'] else 'inserted'} | "
          f"{report['delta']['bytes'] / report['file_bytes'] * 100:.2f} % | {equal} of {len(shared)} | "
          f"{'yes' if a.get('VNND') == b.get('VNND') else 'NO'} | {localized['updated']} / {localized['full']} | "
          f"{medians['updated']:.4g} / {medians['full']:.4g} | {medians['updated'] / medians['full']:.3f} |")
if city:
    out = city_out
    full_s, full_mb = time_of(f"{out}/build_full.time")
    print()
    print(f"Full build of the city: {full_s:.1f} s, {full_mb:.0f} MB peak")
    print()
    print("| growth | update (s) | of the full build | peak (MB) | of the full build's | delta (MB) | of the index | apply (s) | apply peak (MB) |")
    print("|---|---|---|---|---|---|---|---|---|")
    for percent in (1, 10):
        s, mb = time_of(f"{out}/update_{percent}.time")
        apply_s, apply_mb = time_of(f"{out}/apply_{percent}.time")
        report = json.load(open(f"{out}/update_{percent}.log"))
        delta = report["delta"]["bytes"]
        print(f"| {percent} % | {s:.1f} | {s / full_s:.2f} | {mb:.0f} | {mb / full_mb:.2f} | {delta / 1e6:.1f} | "
              f"{delta / report['file_bytes'] * 100:.2f} % | {apply_s:.1f} | {apply_mb:.0f} |")
PY
