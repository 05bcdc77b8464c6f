#!/usr/bin/env bash
# The latency budget as the paper's anytime experiment: every query localized with
# --budget-ms 5, 10, 20, 50 and without a budget, on one thread, on herz_jesu_p25 (stored
# features, known camera), sceaux_castle (stored features, EXIF focal prior) and, when given,
# a generated city. Prints a table per data set (bench/summarize_runs.py: localized share,
# errors, median and p90 times) and plots localized share against median time per query
# (cwloc-plot anytime), one series per data set, as WORKDIR/anytime_budget.png.
#
#   bench/anytime_benchmark.sh WORKDIR [CITY_DIR]
#   bench/anytime_benchmark.sh /tmp/anytime /tmp/city10m
#
# CITY_DIR holds a bench/city_benchmark.sh city (CITY_DIR/city, CITY_DIR/city.cwl).
set -euo pipefail
top="$(cd "$(dirname "$0")/.." && pwd)"
bin="${CWLOC_BIN:-$top/build/bin}"
[ $# -ge 1 ] || { echo "usage: $0 WORKDIR [CITY_DIR]" >&2; exit 2; }
work="$1" city="${2:-}"
data="$top/../shared/data"
budgets=(5 10 20 50 0)
mkdir -p "$work/runs"
for set in herz_jesu_p25 sceaux_castle; do
  [ -f "$work/$set.cwl" ] || "$bin/cwloc-index" build --model "$data/$set/mapping_model/bin" \
    --database "$data/$set/database.db" -o "$work/$set.cwl" >/dev/null
done

# sweep NAME GT SCALE -- cwloc-localize arguments: one run per budget, then one report.
sweep() {
  local name="$1" gt="$2" scale="$3" args=()
  shift 4
  for budget in "${budgets[@]}"; do
    local label="T=${budget} ms" run="$work/runs/$name-$budget.jsonl" status=0
    [ "$budget" = 0 ] && label="no budget"
    echo "## $name, $label" >&2
    "$bin/cwloc-localize" --threads 1 -q --budget-ms "$budget" "$@" -o "$run" || status=$?
    [ "$status" -le 1 ] || exit "$status"
    args+=(--results "$run" --label "$label")
  done
  local scale_args=()
  [ -n "$scale" ] && scale_args=(--scale "$scale")
  "$bin/cwloc-eval" --json "${args[@]}" --gt "$gt" "${scale_args[@]}" >"$work/$name.json"
  echo
  echo "### $name"
  "$top/bench/summarize_runs.py" "$work/$name.json"
}

hj="$data/herz_jesu_p25" sc="$data/sceaux_castle"
# Cached as if read from disk (large folios), not as the indexer left them.
"$top/bench/reload_index.py" "$work/herz_jesu_p25.cwl" "$work/sceaux_castle.cwl" \
  ${city:+"$city/city.cwl"}
sweep herz_jesu_p25 "$hj/queries_gt.txt" "$hj/scale_to_metres.txt" -- \
  --index "$work/herz_jesu_p25.cwl" --database "$hj/database.db" \
  --query-list "$hj/queries_with_intrinsics.txt"
sweep sceaux_castle "$sc/queries_gt.txt" "$sc/scale_to_metres.txt" -- \
  --index "$work/sceaux_castle.cwl" --database "$sc/database.db" --query-list "$sc/query_list.txt"
plot=(--report "$work/herz_jesu_p25.json" --series "herz_jesu_p25 (5 queries)"
  --report "$work/sceaux_castle.json" --series "sceaux_castle (3 queries, focal prior)")
if [ -n "$city" ]; then
  sweep city "$city/city/queries_gt.txt" "$city/city/scale_to_metres.txt" -- \
    --index "$city/city.cwl" --database "$city/city/database.db" \
    --query-list "$city/city/queries_with_intrinsics.txt"
  plot+=(--report "$work/city.json" --series "generated city ($(basename "$city"), 50 queries)")
fi
"$bin/cwloc-plot" anytime "${plot[@]}" --x-scale log \
  --title "--budget-ms 5, 10, 20, 50 ms and none: localized share against median time (1 thread)" \
  -o "$work/anytime_budget.png"
