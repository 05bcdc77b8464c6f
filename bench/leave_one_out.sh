#!/usr/bin/env bash
# Leave-one-out on real photos: how the query photo's SIFT settings affect localization. Every
# photo I of a data set is a query in turn, from its JPEG (all_images/I), against an index of
# the full model with I deleted (colmap image_deleter; no re-adjustment, so I's pose in
# full_model is its ground truth). Each configuration (a label and cwloc-localize flags) runs on
# every photo, one process per photo (each photo has its own index), on one thread, with
# --max-image-size 1600 (the data sets' extraction setting) and the set's camera handling:
# herz_jesu_p25 a focal prior --focal 1375.77 (its JPEGs have no EXIF), others none (EXIF).
#
#   bench/leave_one_out.sh WORKDIR [SET ...] [-- LABEL:FLAGS ...]
#   CWLOC_BIN=/tmp/bin bench/leave_one_out.sh /tmp/loo
#   bench/leave_one_out.sh /tmp/loo herz_jesu_p25 -- "fast:--first-octave 0 --max-features 6000"
#
# SET: a folder name in ../shared/data or a path to a data set with full_model/bin, database.db,
# all_images/ and scale_to_metres.txt (default: herz_jesu_p25 sceaux_castle).
# LABEL:FLAGS (default):
#   compatible:--first-octave -1 --max-features 6000   (COLMAP's features, as in the database)
#   fast:--first-octave 0 --max-features 6000
#   fast-2000:--first-octave 0 --max-features 2000
#   half:--first-octave 1 --max-features 6000
# Writes WORKDIR/SET/I/{model,index.cwl} (kept: built only when missing), WORKDIR/SET/gt.txt
# (every image's full_model pose, queries_gt.txt format) and WORKDIR/SET/LABEL.jsonl (rewritten
# on every run; photos outer, configurations inner, so load drift hits every configuration).
# Prints per set cwloc-eval's table of all configurations, then per configuration the medians of
# times_ms.extraction, times_ms.total and matches.features, and every photo not localized with
# its failure_reason.
set -euo pipefail
top="$(cd "$(dirname "$0")/.." && pwd)"
bin="${CWLOC_BIN:-$top/build/bin}"
usage="usage: $0 WORKDIR [SET ...] [-- LABEL:FLAGS ...]"
[ $# -ge 1 ] || { echo "$usage" >&2; exit 2; }
work="$(realpath -m "$1")"
shift
sets=()
while [ $# -gt 0 ] && [ "$1" != -- ]; do sets+=("$1"); shift; done
[ $# -gt 0 ] && shift
configs=("$@")
[ ${#sets[@]} -gt 0 ] || sets=(herz_jesu_p25 sceaux_castle)
[ ${#configs[@]} -gt 0 ] || configs=(
  "compatible:--first-octave -1 --max-features 6000"
  "fast:--first-octave 0 --max-features 6000"
  "fast-2000:--first-octave 0 --max-features 2000"
  "half:--first-octave 1 --max-features 6000")
for config in "${configs[@]}"; do
  [[ "$config" =~ ^[A-Za-z0-9._-]+: ]] || { echo "$0: bad configuration '$config' (LABEL:FLAGS)" >&2; exit 2; }
done
for tool in cwloc-index cwloc-localize cwloc-eval; do
  [ -x "$bin/$tool" ] || { echo "$0: $bin/$tool not found (build first, or set CWLOC_BIN)" >&2; exit 2; }
done
command -v colmap >/dev/null || { echo "$0: colmap not found" >&2; exit 2; }
export QT_QPA_PLATFORM=offscreen   # colmap is a Qt program; no X server here

for set in "${sets[@]}"; do
  data="$set"
  [ -d "$data" ] || data="$top/../shared/data/$set"
  data="$(realpath "$data")"
  name="$(basename "$data")"
  for f in full_model/bin database.db all_images scale_to_metres.txt; do
    [ -e "$data/$f" ] || { echo "$0: $data/$f is missing" >&2; exit 2; }
  done
  camera=()
  case "$name" in
    herz_jesu_p25) camera=(--focal 1375.77) ;;  # as docs/benchmarks.md, "Photo in, pose out"
  esac
  out="$work/$name"
  mkdir -p "$out"

  # Ground truth: every image's pose and camera in full_model, as queries_gt.txt.
  if [ ! -s "$out/gt.txt" ]; then
    mkdir -p "$out/full_txt"
    colmap model_converter --input_path "$data/full_model/bin" --output_path "$out/full_txt" \
      --output_type TXT >"$out/full_txt/log" 2>&1
    python3 - "$out/full_txt" >"$out/gt.txt.tmp" <<'PY'
import sys
d = sys.argv[1]
cams = {}
for line in open(f"{d}/cameras.txt"):
    if line.strip() and not line.startswith("#"):
        f = line.split()
        cams[f[0]] = " ".join(f[1:])
lines = open(f"{d}/images.txt").read().split("\n")
while lines and lines[0].startswith("#"):
    lines.pop(0)
print("# Ground-truth poses of all images from full_model (leave-one-out).")
print("# NAME QW QX QY QZ TX TY TZ CAMERA_MODEL WIDTH HEIGHT PARAMS...")
rows = []
for line in lines[0::2]:  # image line, then its POINTS2D line (possibly empty)
    f = line.split()
    if len(f) == 10:
        rows.append(f"{f[9]} {' '.join(f[1:8])} {cams[f[8]]}")
print("\n".join(sorted(rows)))
PY
    mv "$out/gt.txt.tmp" "$out/gt.txt"
  fi
  mapfile -t images < <(awk '!/^#/ && NF { print $1 }' "$out/gt.txt")
  echo "## $name: ${#images[@]} photos, ${#configs[@]} configurations" >&2

  # One model and index per photo, without it.
  for image in "${images[@]}"; do
    [ -f "$data/all_images/$image" ] || { echo "$0: $data/all_images/$image is missing" >&2; exit 2; }
    dir="$out/$image"
    [ -f "$dir/index.cwl" ] && continue
    echo "## $name: index without $image" >&2
    mkdir -p "$dir/model"
    echo "$image" >"$dir/deleted.txt"
    colmap image_deleter --input_path "$data/full_model/bin" --output_path "$dir/model" \
      --image_names_path "$dir/deleted.txt" >"$dir/image_deleter.log" 2>&1
    "$bin/cwloc-index" build --model "$dir/model" --database "$data/database.db" \
      -o "$dir/index.cwl.tmp" >"$dir/index.log"
    mv "$dir/index.cwl.tmp" "$dir/index.cwl"
  done

  for config in "${configs[@]}"; do rm -f "$out/${config%%:*}.jsonl"; done
  for image in "${images[@]}"; do
    dir="$out/$image"
    # Cached as if read from disk (large folios), not as the indexer left it.
    "$top/bench/reload_index.py" "$dir/index.cwl"
    for config in "${configs[@]}"; do
      label="${config%%:*}" flags="${config#*:}" status=0
      # shellcheck disable=SC2086
      "$bin/cwloc-localize" --index "$dir/index.cwl" --image "$data/all_images/$image" \
        --max-image-size 1600 "${camera[@]}" $flags --threads 1 -q -o "$dir/$label.jsonl" ||
        status=$?
      [ "$status" -le 1 ] || { echo "$0: cwloc-localize failed on $name/$image ($label)" >&2; exit "$status"; }
      cat "$dir/$label.jsonl" >>"$out/$label.jsonl"
    done
  done

  echo
  echo "### $name (leave-one-out, ${#images[@]} photos from all_images/${camera[*]:+, ${camera[*]}})"
  eval_args=() labels=()
  for config in "${configs[@]}"; do
    label="${config%%:*}"
    labels+=("$label")
    eval_args+=(--results "$out/$label.jsonl" --label "$label")
  done
  "$bin/cwloc-eval" "${eval_args[@]}" --gt "$out/gt.txt" --scale "$data/scale_to_metres.txt"
  echo
  python3 - "$out" "${configs[@]}" <<'PY'
import json, statistics, sys
out, configs = sys.argv[1], sys.argv[2:]
def med(values):
    values = [v for v in values if v is not None]
    return statistics.median(values) if values else float("nan")
print("| config | flags | median extraction ms | median total ms | median features |")
print("|---|---|---|---|---|")
failures = []
for config in configs:
    label, flags = config.split(":", 1)
    recs = [json.loads(l) for l in open(f"{out}/{label}.jsonl") if l.strip()]
    times = [r.get("times_ms") or {} for r in recs]
    print(f"| {label} | {flags.strip()} | {med([t.get('extraction') for t in times]):.0f} "
          f"| {med([t.get('total') for t in times]):.0f} "
          f"| {med([(r.get('matches') or {}).get('features') for r in recs]):.0f} |")
    failures += [(label, r["name"], r.get("failure_reason")) for r in recs if not r.get("success")]
for label, name, reason in failures:
    print(f"not localized: {label} {name}: {reason}")
PY
done
