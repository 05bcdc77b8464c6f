#!/usr/bin/env bash
# Uncalibrated queries against COLMAP, per query and per group of data sets: runs
# bench/colmap_peer.sh --unknown-focal on each data set (each query its own camera, only the
# image size known, COLMAP's image_registrator as the peer), then prints one table per group
# and a summary: localized, median and worst position error of each tool and their ratios.
# A group is the data sets whose names differ only in a _qN split suffix (make_photo_dataset.sh
# --query-offset), so that each photo of a small collection is a query once.
#
#   bench/internet_benchmark.sh WORKDIR DATASET_DIR...
#   CWLOC_BIN=build-a/bin bench/internet_benchmark.sh /tmp/web ../shared/data/sacre_coeur_web_q*
#
# WORKDIR/NAME holds each data set's run (logs, poses, cwloc.jsonl); WORKDIR/summary.md the tables.
set -euo pipefail
top="$(cd "$(dirname "$0")/.." && pwd)"
[ $# -ge 2 ] || { echo "usage: $0 WORKDIR DATASET_DIR..." >&2; exit 2; }
work="$(realpath -m "$1")"
shift
mkdir -p "$work"
runs=()
for data in "$@"; do
  name="$(basename "$(realpath "$data")")"
  echo "## $name" >&2
  "$top/bench/colmap_peer.sh" --unknown-focal "$work/$name" "$data" >"$work/$name.log" 2>&1 ||
    { echo "$0: colmap_peer.sh failed on $data, see $work/$name.log" >&2; exit 1; }
  runs+=("$work/$name")
done

python3 - "${runs[@]}" <<'PY' | tee "$work/summary.md"
import json, re, statistics, sys
from collections import OrderedDict

groups = OrderedDict()
for run in sys.argv[1:]:
    name = run.rstrip("/").split("/")[-1]
    group = re.sub(r"_q\d+(?=_|$)", "", name)
    report = json.load(open(f"{run}/peer_eval.json"))
    per_tool = {r["label"]: {q["name"]: q for q in r["per_query"]} for r in report["runs"]}
    cwloc = {}
    for line in open(f"{run}/cwloc.jsonl"):
        if line.strip():
            r = json.loads(line)
            cwloc[r["name"]] = r
    truth = {}
    for line in open(report["ground_truth"]["path"]):
        f = line.split()
        if f and not f[0].startswith("#"):
            truth[f[0]] = (int(f[9]), float(f[11]))
    rows = groups.setdefault(group, [])
    for query in sorted(per_tool["cwloc"]):
        r = cwloc.get(query, {})
        depth = r.get("focal_depth") or {}
        rows.append({"split": name, "query": query, "colmap": per_tool["colmap"].get(query),
                     "cwloc": per_tool["cwloc"][query], "width": truth[query][0],
                     "focal_gt": truth[query][1],
                     "focal": r["camera"]["params"][0] if r.get("success") else None,
                     "inliers": r.get("num_inliers"), "weak": depth.get("weakly_constrained"),
                     "images": r.get("matches", {}).get("back_matched_images")})

def error(entry):
    return entry["position_error"] if entry and entry["status"] == "localized" else None

def fmt(value, digits=4):
    return "not localized" if value is None else f"{value:.{digits}f}"

for group, rows in groups.items():
    print(f"### {group}\n")
    print("| query | f / width | COLMAP position error | cwloc position error | cwloc focal (truth) | inliers | images back-matched | weakly constrained |")
    print("|---|---|---|---|---|---|---|---|")
    for row in rows:
        focal = "-" if row["focal"] is None else f"{row['focal']:.0f} ({row['focal_gt']:.0f})"
        print(f"| {row['query']} | {row['focal_gt'] / row['width']:.1f} | {fmt(error(row['colmap']))} | "
              f"{fmt(error(row['cwloc']))} | {focal} | {row['inliers']} | {row['images']} | "
              f"{'yes' if row['weak'] else 'no'} |")
    print()
print("| data set | queries | COLMAP localized | cwloc localized | COLMAP median / worst | cwloc median / worst | median ratio | worst ratio |")
print("|---|---|---|---|---|---|---|---|")
for group, rows in groups.items():
    summary = {}
    for tool in ("colmap", "cwloc"):
        errors = [e for e in (error(row[tool]) for row in rows) if e is not None]
        summary[tool] = (len(errors), statistics.median(errors) if errors else None,
                         max(errors) if errors else None)
    (nc, mc, wc), (nw, mw, ww) = summary["colmap"], summary["cwloc"]
    ratio = lambda a, b: f"{a / b:.2f}" if a is not None and b else "-"
    print(f"| {group} | {len(rows)} | {nc} | {nw} | {fmt(mc)} / {fmt(wc)} | {fmt(mw)} / {fmt(ww)} | "
          f"{ratio(mw, mc)} | {ratio(ww, wc)} |")
PY
