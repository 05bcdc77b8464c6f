#!/usr/bin/env bash
# Matching or estimation? Four poses per query (issue #41, docs/benchmarks.md, "Internet
# photos"): {cwloc's, COLMAP's} correspondences x {cwloc's, COLMAP's} estimator, on runs of
# bench/colmap_peer.sh (bench/internet_benchmark.sh makes one per data set).
#   cwloc x cwloc:   cwloc-cross-pose fits cwloc's pose stage to the correspondences cwloc's
#                    matcher gave it (Localize's own pose, refit);
#   COLMAP x cwloc:  cwloc-cross-pose fits cwloc's pose stage to the 2D-3D pairs COLMAP's
#                    image_registrator used (its registered model's query points);
#   cwloc x COLMAP:  COLMAP's image_registrator on a copy of the run's database whose only
#                    query-to-model matches are cwloc's correspondences (each a match between
#                    the query's feature and the mapping image's keypoint that the 3D point's
#                    view is; --Mapper.min_num_matches 1, so that no pair is dropped for having
#                    few of them), with the run's query cameras;
#   COLMAP x COLMAP: the run's COLMAP registration.
#
#   bench/cross_estimation.sh WORKDIR DATASET_DIR...
#   (WORKDIR/NAME: bench/colmap_peer.sh's run of DATASET_DIR, e.g. bench/internet_benchmark.sh's)
#
# Prints a table per data set and a pooled summary; writes WORKDIR/NAME/cross.jsonl (both cwloc
# fits), cwloc_pairs.txt, swap.db and swap_registered/ (COLMAP on cwloc's correspondences).
set -euo pipefail
top="$(cd "$(dirname "$0")/.." && pwd)"
bin="${CWLOC_BIN:-$top/build/bin}"
[ $# -ge 2 ] || { echo "usage: $0 WORKDIR DATASET_DIR..." >&2; exit 2; }
work="$(realpath -m "$1")"
shift
[ -x "$bin/cwloc-cross-pose" ] || { echo "$0: $bin/cwloc-cross-pose not found (build first)" >&2; exit 2; }
command -v colmap >/dev/null || { echo "$0: colmap not found" >&2; exit 2; }
export QT_QPA_PLATFORM=offscreen # colmap is a Qt program; no X server here

runs=()
for data in "$@"; do
  data="$(realpath "$data")"
  name="$(basename "$data")"
  run="$work/$name"
  for f in peer.db colmap_registered; do
    [ -e "$run/$f" ] || { echo "$0: $run/$f is missing (run bench/colmap_peer.sh first)" >&2; exit 2; }
  done
  echo "## $name" >&2
  # The run's index again with each view's keypoint (VKXY), to name the views to COLMAP.
  "$bin/cwloc-index" build --model "$data/mapping_model/bin" --database "$run/peer.db" \
    --keypoints -o "$run/cross.cwl" >"$run/cross_index.log"
  "$bin/cwloc-cross-pose" --index "$run/cross.cwl" --database "$run/peer.db" \
    --query-list "$data/query_list.txt" --mapping-model "$data/mapping_model/bin" \
    --colmap-model "$run/colmap_registered" -o "$run/cross.jsonl" --pairs "$run/cwloc_pairs.txt"

  # The run's database with cwloc's correspondences as the only matches of the queries.
  install -m 644 "$run/peer.db" "$run/swap.db"
  python3 - "$run/swap.db" "$data/query_list.txt" "$run/cwloc_pairs.txt" <<'PY'
import collections, sqlite3, struct, sys
db_path, list_path, pairs_path = sys.argv[1:4]
db = sqlite3.connect(db_path)
names = [line.split()[0] for line in open(list_path) if line.strip()]
ids = {name: db.execute("SELECT image_id FROM images WHERE name = ?", (name,)).fetchone()[0]
       for name in names}
query_ids = set(ids.values())
for table in ("matches", "two_view_geometries"):
    for pair_id, in db.execute(f"SELECT pair_id FROM {table}").fetchall():
        if pair_id // 2147483647 in query_ids or pair_id % 2147483647 in query_ids:
            db.execute(f"DELETE FROM {table} WHERE pair_id = ?", (pair_id,))
by_pair = collections.defaultdict(list)
for line in open(pairs_path):
    name, feature, image_id, point2D = line.split()
    by_pair[(ids[name], int(image_id))].append((int(feature), int(point2D)))
identity = struct.pack("<9d", 1, 0, 0, 0, 1, 0, 0, 0, 1)
for (query, image), matches in by_pair.items():
    if query > image:  # COLMAP's pair order: the smaller image id first
        query, image = image, query
        matches = [(b, a) for a, b in matches]
    pair_id = query * 2147483647 + image
    data = b"".join(struct.pack("<2I", a, b) for a, b in matches)
    db.execute("INSERT INTO matches (pair_id, rows, cols, data) VALUES (?, ?, 2, ?)",
               (pair_id, len(matches), data))
    db.execute("INSERT INTO two_view_geometries (pair_id, rows, cols, data, config, F, E, H) "
               "VALUES (?, ?, 2, ?, 2, ?, ?, ?)",
               (pair_id, len(matches), data, identity, identity, identity))
db.commit()
PY
  rm -rf "$run/swap_registered" "$run/swap_registered_txt"
  mkdir -p "$run/swap_registered" "$run/swap_registered_txt"
  colmap image_registrator --database_path "$run/swap.db" --input_path "$data/mapping_model/bin" \
    --output_path "$run/swap_registered" --Mapper.num_threads 1 --Mapper.min_num_matches 1 \
    >"$run/swap_registrator.log" 2>&1
  colmap model_converter --input_path "$run/swap_registered" \
    --output_path "$run/swap_registered_txt" --output_type TXT >/dev/null 2>&1
  # Each column's poses (NAME QW QX QY QZ TX TY TZ), scored by cwloc-eval.
  python3 - "$run" <<'PY'
import json, sys
run = sys.argv[1]
files = {key: open(f"{run}/cross_{key}_poses.txt", "w") for key in ("cwloc", "colmap")}
for line in open(f"{run}/cross.jsonl"):
    r = json.loads(line)
    for key, out in files.items():
        fit = r.get(key) or {}
        if fit.get("success"):
            out.write(" ".join([r["name"]] + [repr(v) for v in fit["qvec"] + fit["tvec"]]) + "\n")
PY
  awk 'NR == FNR { query[$1] = 1; next } /^#/ { next }
       { n++ } n % 2 == 1 && ($10 in query) { print $10, $2, $3, $4, $5, $6, $7, $8 }' \
    "$data/query_list.txt" "$run/swap_registered_txt/images.txt" >"$run/cross_swap_poses.txt"
  "$bin/cwloc-eval" --results "$run/cross_cwloc_poses.txt" --label "cwloc x cwloc" \
    --results "$run/cross_colmap_poses.txt" --label "COLMAP x cwloc" \
    --results "$run/cross_swap_poses.txt" --label "cwloc x COLMAP" \
    --results "$run/colmap_poses.txt" --label "COLMAP x COLMAP" \
    --gt "$data/queries_gt.txt" --scale "$data/scale_to_metres.txt" --json >"$run/cross_eval.json"
  runs+=("$data" "$run")
done

python3 - "${runs[@]}" <<'PY'
import json, math, re, statistics, sys
from collections import OrderedDict

columns = ("cwloc x cwloc", "COLMAP x cwloc", "cwloc x COLMAP", "COLMAP x COLMAP")
groups = OrderedDict()
for run in sys.argv[2::2]:
    name = run.rstrip("/").split("/")[-1]
    group = re.sub(r"_q\d+(?=_|$)", "", name)
    report = json.load(open(f"{run}/cross_eval.json"))
    per_column = {r["label"]: {q["name"]: q for q in r["per_query"]} for r in report["runs"]}
    pairs = {r["name"]: r for r in map(json.loads, open(f"{run}/cross.jsonl"))}
    for query in sorted(pairs):
        def error(column):
            entry = per_column[column].get(query)
            return entry["position_error"] if entry and entry["status"] == "localized" else None
        r = pairs[query]
        groups.setdefault(group, []).append({
            "query": query, "errors": [error(c) for c in columns],
            "pairs": ((r.get("cwloc") or {}).get("correspondences"), r["colmap_pairs"],
                      r["colmap_pairs_mapped"])})

def fmt(e):
    return "-" if e is None else f"{e:.4f}"

for group, rows in groups.items():
    print(f"### {group}\n")
    print("| query | " + " | ".join(columns) + " | correspondences cwloc / COLMAP (mapped) |")
    print("|---|" + "---|" * len(columns) + "---|")
    for row in rows:
        mine, theirs, mapped = row["pairs"]
        print(f"| {row['query']} | " + " | ".join(fmt(e) for e in row["errors"]) +
              f" | {mine} / {theirs} ({mapped}) |")
    print()
every = [row for rows in groups.values() for row in rows]
both = [row for row in every if all(e is not None for e in row["errors"])]
print("Pooled: localized; over the queries every column localized, median / worst position error")
print("and the geometric mean of each column's error over COLMAP x COLMAP's.\n")
print("| | " + " | ".join(columns) + " |")
print("|---|" + "---|" * len(columns))
print(f"| localized (of {len(every)}) | " +
      " | ".join(str(sum(row["errors"][i] is not None for row in every)) for i in range(4)) + " |")
if both:
    for label, pick in (("median", statistics.median), ("worst", max)):
        print(f"| {label} ({len(both)} queries) | " +
              " | ".join(f"{pick(row['errors'][i] for row in both):.4f}" for i in range(4)) + " |")
    def geomean(i):
        logs = [math.log(max(row["errors"][i], 1e-12) / max(row["errors"][3], 1e-12)) for row in both]
        return math.exp(sum(logs) / len(logs))
    print("| over COLMAP x COLMAP (geometric mean) | " +
          " | ".join(f"{geomean(i):.2f}x" for i in range(4)) + " |")
PY
