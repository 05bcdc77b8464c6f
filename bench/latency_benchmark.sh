#!/usr/bin/env bash
# Localization latency, old build against new in one run: the real queries (herz_jesu_p25 from
# their stored features and from their JPEGs, sceaux_castle from its features with the
# database's EXIF focal prior and with the known camera) and, when given,
# a generated city. Each round runs every workload with each build, one thread, alternating
# builds so that load drift hits both; the table gives, per workload and build, the localized
# count and the medians over queries and rounds of the time after the features are known
# (times_ms.total minus extraction) and of each stage.
#
#   bench/latency_benchmark.sh OLD_BIN NEW_BIN WORKDIR [CITY_DIR]
#   bench/latency_benchmark.sh /tmp/old/bin build/bin /tmp/latency /tmp/city10m
#
# CITY_DIR holds a bench/city_benchmark.sh city (CITY_DIR/city, CITY_DIR/city.cwl). ROUNDS
# (default 3) sets the rounds; EXTRA_NEW adds flags to the new build's runs only.
set -euo pipefail
top="$(cd "$(dirname "$0")/.." && pwd)"
[ $# -ge 3 ] || { echo "usage: $0 OLD_BIN NEW_BIN WORKDIR [CITY_DIR]" >&2; exit 2; }
old="$1" new="$2" work="$3" city="${4:-}"
rounds="${ROUNDS:-3}"
data="$top/../shared/data"
mkdir -p "$work"
hj="$data/herz_jesu_p25" sc="$data/sceaux_castle"
for set in herz_jesu_p25 sceaux_castle; do
  [ -f "$work/$set.cwl" ] || "$new/cwloc-index" build --model "$data/$set/mapping_model/bin" \
    --database "$data/$set/database.db" -o "$work/$set.cwl" >/dev/null
done

# run LABEL BIN EXTRA -- cwloc-localize arguments: appends to WORKDIR/LABEL.jsonl
run() {
  local label="$1" bin="$2" extra="$3" status=0
  shift 4
  # shellcheck disable=SC2086
  "$bin/cwloc-localize" --threads 1 -q "$@" $extra >>"$work/$label.jsonl" || status=$?
  [ "$status" -le 1 ] || exit "$status"
}

workloads=(hj-features hj-jpeg sc-features sc-known)
[ -n "$city" ] && workloads+=(city)
# Cached as if read from disk (large folios), not as the indexer left them.
indexes=("$work/herz_jesu_p25.cwl" "$work/sceaux_castle.cwl")
[ -n "$city" ] && indexes+=("$city/city.cwl")
"$top/bench/reload_index.py" "${indexes[@]}"
rm -f "$work"/*.jsonl
for ((round = 1; round <= rounds; round++)); do
  for build in old new; do
    bin="$old" extra=""
    [ "$build" = new ] && bin="$new" extra="${EXTRA_NEW:-}"
    echo "## round $round, $build" >&2
    run "hj-features.$build" "$bin" "$extra" -- --index "$work/herz_jesu_p25.cwl" \
      --database "$hj/database.db" --query-list "$hj/queries_with_intrinsics.txt"
    run "hj-jpeg.$build" "$bin" "$extra" -- --index "$work/herz_jesu_p25.cwl" \
      --image-list "$hj/queries_with_intrinsics.txt" --image-dir "$hj/query_images"
    run "sc-features.$build" "$bin" "$extra" -- --index "$work/sceaux_castle.cwl" \
      --database "$sc/database.db" --query-list "$sc/query_list.txt"
    run "sc-known.$build" "$bin" "$extra" -- --index "$work/sceaux_castle.cwl" \
      --database "$sc/database.db" --query-list "$sc/queries_with_intrinsics.txt"
    if [ -n "$city" ]; then
      run "city.$build" "$bin" "$extra" -- --index "$city/city.cwl" \
        --database "$city/city/database.db" --query-list "$city/city/queries_with_intrinsics.txt"
    fi
  done
done

python3 - "$work" "${workloads[@]}" <<'PY'
import json, statistics, sys
work, workloads = sys.argv[1], sys.argv[2:]
stages = ["forward_knn", "query_tree", "back_matching", "pose"]
def q(values, p):
    values = sorted(values)
    return values[min(len(values) - 1, int(p * len(values)))]
print("| workload | build | localized | features (median) | median ms | p90 ms | "
      + " / ".join(stages) + " (median ms) |")
print("|---|---|---|---|---|---|---|")
for w in workloads:
    medians = {}
    for build in ("old", "new"):
        records = [json.loads(l) for l in open(f"{work}/{w}.{build}.jsonl")]
        after = [r["times_ms"]["total"] - r["times_ms"]["extraction"] for r in records]
        names = {r["name"] for r in records}
        localized = {r["name"] for r in records if r["success"]}
        # a query counts as localized when it was in every round
        rounds = len(records) // len(names)
        every = [n for n in names if sum(r["name"] == n and r["success"] for r in records) == rounds]
        per_stage = " / ".join(
            f'{statistics.median(r["times_ms"][s] for r in records):.2f}' for s in stages)
        features = statistics.median(r["matches"]["features"] for r in records)
        medians[build] = statistics.median(after)
        print(f"| {w} | {build} | {len(every)}/{len(names)} | {features:.0f} | "
              f"{medians[build]:.2f} | {q(after, 0.9):.2f} | {per_stage} |")
    print(f"| {w} | old / new | | | {medians['old'] / medians['new']:.2f}x | | |")
PY
