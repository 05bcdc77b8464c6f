#!/usr/bin/env bash
# Generated-city benchmark: build the index of a cwloc-synth city, then localize its queries
# with the cluster-wise matcher and the global-ratio baseline on one thread, and print the
# measurements (index build time, size, open time, localized share, errors, time per query).
#
#   bench/city_benchmark.sh WORKDIR [cwloc-synth knobs...]
#   bench/city_benchmark.sh /tmp/city10m --views 10000000 --queries 50
#   bench/city_benchmark.sh /tmp/rep --views 300000 --repetition 0.6 --motifs 64 --queries 100
#
# The city is generated only when WORKDIR/city does not exist yet.
set -euo pipefail
top="$(cd "$(dirname "$0")/.." && pwd)"
bin="${CWLOC_BIN:-$top/build/bin}"
work="$1"
shift
mkdir -p "$work"
city="$work/city"
index="$work/city.cwl"
timing() { /usr/bin/time -f "%e s wall, %M KB peak" "$@"; }

if [ ! -d "$city" ]; then
  echo "## generating the city: cwloc-synth $*"
  timing "$bin/cwloc-synth" -o "$city" "$@"
fi

echo "## building the index"
timing "$bin/cwloc-index" build --model "$city/mapping_model/bin" --database "$city/database.db" -o "$index"
timing "$bin/cwloc-index" verify "$index"
"$bin/cwloc-open-bench" "$index" 200
# Cached as if read from disk (large folios), not as the indexer left it.
"$top/bench/reload_index.py" "$index"

for matcher in cluster-wise global-ratio; do
  echo "## localizing with --matcher $matcher (1 thread)"
  status=0
  timing "$bin/cwloc-localize" --index "$index" --database "$city/database.db" \
    --query-list "$city/queries_with_intrinsics.txt" --matcher "$matcher" --threads 1 \
    -o "$work/results_$matcher.jsonl" -q || status=$?
  [ "$status" -le 1 ] || exit "$status"
done

echo "## evaluation"
"$bin/cwloc-eval" --results "$work/results_cluster-wise.jsonl" --label cluster-wise \
  --results "$work/results_global-ratio.jsonl" --label global-ratio \
  --gt "$city/queries_gt.txt" --scale "$city/scale_to_metres.txt" \
  --model "$city/mapping_model/bin" --gt-points "$city/queries_gt_points.txt"
