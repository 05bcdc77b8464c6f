#!/usr/bin/env bash
# The paper's experiments on a generated city with strong global repetition (60 % of facade
# points are instances of 64 motifs repeated city-wide), printed as markdown tables with PNGs:
#   Table 1  exhaustive local matching per cluster (--matcher cluster-exhaustive) for 1, 50 and
#            500 clusters, against global matching (kd-forest + 1-ratio, --matcher global-ratio)
#   Table 2  the cluster-wise ratio test with 1, 50, 500 clusters and one image per cluster
#   Table 3  location recognition top-k for N_F = 50, 100, 200, 500 and all features
#   Fig. 4   anytime curves: localized queries against time per query, sweeping N_F (5 to 500)
#            and N_B (25 to 500); below N_F = 50 is where this city starts to lose queries
#
#   bench/paper_experiments.sh WORKDIR
#   CWLOC_LOCALIZE_FLAGS="--back-matching full" bench/paper_experiments.sh WORKDIR2
#
# CWLOC_LOCALIZE_FLAGS are added to every cwloc-localize run (e.g. the paper's full
# back-matching; WORKDIR2 may link WORKDIR's city and indices to reuse them).
# The city and the indices are made only when missing, so reruns only localize. Exhaustive
# matching compares every feature with every view (seconds per query) and runs on
# ${CWLOC_EXHAUSTIVE_THREADS:-2} threads; every other run uses 1 thread, so its times compare.
set -euo pipefail
top="$(cd "$(dirname "$0")/.." && pwd)"
bin="${CWLOC_BIN:-$top/build/bin}"
[ $# -eq 1 ] || { echo "usage: $0 WORKDIR" >&2; exit 2; }
work="$1"
city="$work/city"
runs="$work/runs"
mkdir -p "$runs"

if [ ! -d "$city" ]; then
  echo "## generating the city" >&2
  # 700 features per image give 1,566 images for 576k views: room for 500 clusters.
  "$bin/cwloc-synth" -o "$city" --views 550000 --features-per-image 700 --repetition 0.6 --motifs 64 \
    --queries 100 >&2
fi

# index NAME [cwloc-index build options]: WORKDIR/NAME.cwl, built once.
index() {
  local name="$1"
  shift
  if [ ! -f "$work/$name.cwl" ]; then
    echo "## index $name: cwloc-index build $*" >&2
    "$bin/cwloc-index" build --model "$city/mapping_model/bin" --database "$city/database.db" \
      -o "$work/$name.cwl" "$@" >&2
  fi
}
index per-image
index clusters-1 --clusters 1
index clusters-50 --clusters 50
index clusters-500 --clusters 500

# localize RUN INDEX [cwloc-localize options]: runs/RUN.jsonl on ${threads:-1} threads (exit 1,
# some queries not localized, is fine).
localize() {
  local run="$1" idx="$2" status=0
  shift 2
  echo "## localize $run: $*" >&2
  "$bin/cwloc-localize" --index "$work/$idx.cwl" --database "$city/database.db" \
    --query-list "$city/queries_with_intrinsics.txt" --threads "${threads:-1}" -q -o "$runs/$run.jsonl" "$@" \
    ${CWLOC_LOCALIZE_FLAGS:-} || status=$?
  [ "$status" -le 1 ] || exit "$status"
}

# evaluate REPORT RUN...: one cwloc-eval --json report over the runs, as REPORT.json.
evaluate() {
  local report="$1" args=()
  shift
  for run in "$@"; do args+=(--results "$runs/$run.jsonl" --label "$run"); done
  "$bin/cwloc-eval" --json "${args[@]}" --gt "$city/queries_gt.txt" --scale "$city/scale_to_metres.txt" \
    --model "$city/mapping_model/bin" --gt-points "$city/queries_gt_points.txt" >"$work/$report.json"
}

exhaustive_threads="${CWLOC_EXHAUSTIVE_THREADS:-2}"
for c in 1 50 500; do
  threads="$exhaustive_threads" localize "exhaustive-$c" "clusters-$c" --matcher cluster-exhaustive
done
localize global-ratio per-image --matcher global-ratio
for c in 1 50 500; do localize "cwrt-$c" "clusters-$c"; done
localize cwrt-per-image per-image
for nf in 5 10 20 50 100 300 500; do localize "nf-$nf" per-image --nf "$nf"; done
localize nf-all per-image --nf 4294967295
for nb in 25 50 100 300 500; do localize "nb-$nb" per-image --nb "$nb"; done

evaluate table1 exhaustive-1 exhaustive-50 exhaustive-500 global-ratio
evaluate table2 cwrt-1 cwrt-50 cwrt-500 cwrt-per-image global-ratio
cp "$runs/cwrt-per-image.jsonl" "$runs/nf-200.jsonl"   # the defaults: N_F = N_B = 200
cp "$runs/cwrt-per-image.jsonl" "$runs/nb-200.jsonl"
evaluate table3 nf-50 nf-100 nf-200 nf-500 nf-all
evaluate sweep-nf nf-5 nf-10 nf-20 nf-50 nf-100 nf-200 nf-300 nf-500
evaluate sweep-nb nb-25 nb-50 nb-100 nb-200 nb-300 nb-500

for table in table1 table2 table3; do
  echo
  echo "### $table"
  "$top/bench/summarize_runs.py" "$work/$table.json"
done
echo
echo "### sweeps (Figure 4)"
"$top/bench/summarize_runs.py" "$work/sweep-nf.json" "$work/sweep-nb.json"

"$bin/cwloc-plot" anytime --report "$work/sweep-nf.json" --series "N_F = 5..500 (N_B = 200)" \
  --report "$work/sweep-nb.json" --series "N_B = 25..500 (N_F = 200)" \
  --title "Anytime: localized queries against time per query (1 thread)" -o "$work/anytime.png"
"$bin/cwloc-plot" errors --report "$work/table1.json" \
  --title "Cumulative position error: exhaustive matching per cluster, and global matching" \
  -o "$work/errors_table1.png"
"$bin/cwloc-plot" errors --report "$work/table2.json" \
  --title "Cumulative position error: cluster-wise ratio test by clustering" -o "$work/errors_table2.png"
echo
echo "reports, runs and figures in $work (anytime.png, errors_table1.png, errors_table2.png)"
