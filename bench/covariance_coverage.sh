#!/usr/bin/env bash
# Pose uncertainty on real captures (issue #41, docs/benchmarks.md "Pose uncertainty"): how
# often the true camera centre of a held-out query lies inside its reported 95 % ellipsoid,
# with the index's covariance calibration (cwloc-index build's default) and without it
# (--calibration-samples 0), in every way a query can come:
#   features-known    the database's features, the model camera of queries_with_intrinsics.txt
#   features-unknown  the same with --unknown-focal (P4Pf)
#   photos            the query JPEGs (query_images/): EXIF focal prior, else unknown focal
#   photos-prior      the JPEGs with --focal, when every query has the same focal length
# The queries are never part of the calibration: it leaves model images out.
#
#   bench/covariance_coverage.sh WORKDIR DATASET_DIR...
#   (DATASET_DIR: a folder of ../shared/data's layout, or its name there)
#
# Prints one table row per data set and query source, and the pooled coverage per data set;
# writes WORKDIR/NAME/{calibrated,uncalibrated}.cwl and WORKDIR/NAME/INDEX-RUN.{jsonl,eval.json}.
set -euo pipefail
top="$(cd "$(dirname "$0")/.." && pwd)"
bin="${CWLOC_BIN:-$top/build/bin}"
[ $# -ge 2 ] || { echo "usage: $0 WORKDIR DATASET_DIR..." >&2; exit 2; }
work="$(realpath -m "$1")"
shift
mkdir -p "$work"

for arg in "$@"; do
  data="$arg"
  [ -d "$data" ] || data="$top/../shared/data/$arg"
  [ -d "$data/mapping_model/bin" ] || { echo "$0: $arg: no mapping_model/bin" >&2; exit 2; }
  name="$(basename "$data")"
  run_dir="$work/$name"
  mkdir -p "$run_dir"
  "$bin/cwloc-index" build --model "$data/mapping_model/bin" --database "$data/database.db" \
    -o "$run_dir/calibrated.cwl" --json >"$run_dir/calibrated.build.json"
  "$bin/cwloc-index" build --model "$data/mapping_model/bin" --database "$data/database.db" \
    -o "$run_dir/uncalibrated.cwl" --calibration-samples 0 >/dev/null
  runs=("features-known:--database $data/database.db --query-list $data/queries_with_intrinsics.txt"
        "features-unknown:--database $data/database.db --query-list $data/queries_with_intrinsics.txt --unknown-focal")
  if [ -d "$data/query_images" ]; then
    runs+=("photos:--image-list $data/query_list.txt --image-dir $data/query_images")
    # One focal length for every query (a single camera): also as a prior.
    focals="$(awk '!/^#/ && NF { print $5 }' "$data/queries_with_intrinsics.txt" | sort -u)"
    if [ "$(echo "$focals" | wc -l)" -eq 1 ]; then
      runs+=("photos-prior:--image-list $data/query_list.txt --image-dir $data/query_images --focal $focals")
    fi
  fi
  for index in calibrated uncalibrated; do
    for run in "${runs[@]}"; do
      label="${run%%:*}"
      # shellcheck disable=SC2086  # the flags are words
      "$bin/cwloc-localize" --index "$run_dir/$index.cwl" ${run#*:} --threads 2 -q \
        -o "$run_dir/$index-$label.jsonl" || [ $? -le 1 ]
      "$bin/cwloc-eval" --results "$run_dir/$index-$label.jsonl" --gt "$data/queries_gt.txt" \
        --scale "$data/scale_to_metres.txt" --json >"$run_dir/$index-$label.eval.json"
    done
  done
done

/usr/bin/env python3 - "$bin" "$work" "$@" <<'PY'
import glob, json, os, subprocess, sys
bin_dir, work = sys.argv[1:3]
print("| data set, queries from | queries | calibrated: inside 95 % | uncalibrated |")
print("|---|---|---|---|")
share = lambda t: f"{t[0]}/{t[1]} ({100.0 * t[0] / t[1]:.0f} %)" if t[1] else "-"
scales = []
overall = {"calibrated": [0, 0], "uncalibrated": [0, 0]}
for arg in sys.argv[3:]:
    name = os.path.basename(arg.rstrip("/"))
    totals = {"calibrated": [0, 0], "uncalibrated": [0, 0]}
    for f in sorted(glob.glob(f"{work}/{name}/calibrated-*.eval.json")):
        label = os.path.basename(f)[len("calibrated-"):-len(".eval.json")]
        cells = []
        for index in ("calibrated", "uncalibrated"):
            run = json.load(open(f"{work}/{name}/{index}-{label}.eval.json"))["runs"][0]
            c = run["coverage95"]
            totals[index][0] += c["inside"]
            totals[index][1] += c["with_covariance"]
            overall[index][0] += c["inside"]
            overall[index][1] += c["with_covariance"]
            cells.append(f"{c['inside']}/{c['with_covariance']}")
        print(f"| {name}, {label} | {run['queries']} | {cells[0]} | {cells[1]} |")
    print(f"| **{name}, pooled** | | **{share(totals['calibrated'])}** | {share(totals['uncalibrated'])} |")
    info = json.loads(subprocess.run([f"{bin_dir}/cwloc-index", "info", "--json",
                                      f"{work}/{name}/calibrated.cwl"],
                                     capture_output=True, check=True).stdout)
    modes = info["manifest"]["covariance_calibration"]["modes"]
    scales.append(f"{name}: " + ", ".join(
        f"{m} {v.get('rotation_scale', '-')!s:.4} / {v.get('position_scale', '-')!s:.4} "
        f"({v['localized']} localized)" for m, v in modes.items()))
print(f"| **all, pooled** | | **{share(overall['calibrated'])}** | {share(overall['uncalibrated'])} |")
print("\nThe indexes' calibration (rotation / position scale):")
print("\n".join(scales))
PY
