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
# Prints one table row per data set and query source (the share of truths inside, and the
# median of the position error over the 95 % radius: 0.55 for a calibrated 3D normal), and
# the pooled figures per data set;
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

/usr/bin/env python3 - "$bin" "$work" "$top/../shared/data" "$@" <<'PY'
import glob, json, os, statistics, subprocess, sys
bin_dir, work, shared = sys.argv[1:4]


def scale_of(arg):
    data = arg if os.path.isdir(arg) else os.path.join(shared, arg)
    for line in open(os.path.join(data, "scale_to_metres.txt")):
        if line.startswith("scale "):
            return float(line.split()[1])
    return 1.0


def ratios(records, run, scale):
    """Each localized query's position error over its 95 % radius (a calibrated 3D normal's
    median: 0.55)."""
    radius = {}
    for line in open(records):
        r = json.loads(line) if line.strip() else {}
        if (r.get("covariance") or {}).get("position_radius95"):
            radius[r["name"]] = r["covariance"]["position_radius95"] * scale
    return [q["position_error"] / radius[q["name"]] for q in run["per_query"]
            if q.get("position_error") is not None and q["name"] in radius]


print("| data set, queries from | queries | calibrated: inside 95 % | error / radius, median |"
      " uncalibrated |")
print("|---|---|---|---|---|")
share = lambda t: f"{t[0]}/{t[1]} ({100.0 * t[0] / t[1]:.0f} %)" if t[1] else "-"
scales = []
overall = {"calibrated": [0, 0], "uncalibrated": [0, 0]}
all_ratios = []
for arg in sys.argv[4:]:
    name = os.path.basename(arg.rstrip("/"))
    totals = {"calibrated": [0, 0], "uncalibrated": [0, 0]}
    scale, pooled_ratios = scale_of(arg), []
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
            if index == "calibrated":
                found = ratios(f"{work}/{name}/{index}-{label}.jsonl", run, scale)
                pooled_ratios += found
                cells.append(f"{statistics.median(found):.2f}" if found else "-")
        print(f"| {name}, {label} | {run['queries']} | {' | '.join(cells)} |")
    median = f"{statistics.median(pooled_ratios):.2f}" if pooled_ratios else "-"
    all_ratios.extend(pooled_ratios)
    print(f"| **{name}, pooled** | | **{share(totals['calibrated'])}** | **{median}** | "
          f"{share(totals['uncalibrated'])} |")
    info = json.loads(subprocess.run([f"{bin_dir}/cwloc-index", "info", "--json",
                                      f"{work}/{name}/calibrated.cwl"],
                                     capture_output=True, check=True).stdout)
    modes = info["manifest"]["covariance_calibration"]["modes"]
    scales.append(f"{name}: " + ", ".join(
        f"{m} {v.get('rotation_scale', '-')!s:.4} / {v.get('position_scale', '-')!s:.4} "
        f"({v['localized']} localized)" for m, v in modes.items()))
median = f"{statistics.median(all_ratios):.2f}" if all_ratios else "-"
print(f"| **all, pooled** | | **{share(overall['calibrated'])}** | **{median}** | "
      f"{share(overall['uncalibrated'])} |")
print("\nThe indexes' calibration (rotation / position scale):")
print("\n".join(scales))
PY
