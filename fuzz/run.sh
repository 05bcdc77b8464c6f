#!/usr/bin/env bash
# Runs the libFuzzer targets of a fuzz build (docs/reliability.md) from their seed corpora and
# prints one row per target: executions, seconds, corpus size and the outcome. Exits 1 when a
# target found something; the input that did it is kept in OUT_DIR as crash-*, leak-*,
# timeout-* or oom-* (rerun it: build-fuzz/bin/cwloc-fuzz-TARGET FILE).
#   fuzz/run.sh BUILD_DIR [--seconds S] [--runs N] [--jobs J] [--out OUT_DIR] [TARGET...]
# --seconds bounds each target's time (default 60), --runs its executions (default none); the
# first reached ends it. Targets: index delta colmap_model colmap_database feature_file query_list
# photo georef serve_request (default all that are built). J targets run at once (default 1).
set -euo pipefail
cd "$(dirname "$0")/.."
build="${1:?usage: fuzz/run.sh BUILD_DIR [--seconds S] [--runs N] [--jobs J] [--out DIR] [TARGET...]}"
shift
seconds=60 runs=-1 jobs=1 out=""
targets=()
while [ $# -gt 0 ]; do
  case "$1" in
    --seconds) seconds="$2"; shift 2 ;;
    --runs) runs="$2"; shift 2 ;;
    --jobs) jobs="$2"; shift 2 ;;
    --out) out="$2"; shift 2 ;;
    *) targets+=("$1"); shift ;;
  esac
done
if [ ${#targets[@]} -eq 0 ]; then
  targets=(index delta colmap_model colmap_database feature_file query_list photo georef)
  # cwloc-serve's requests, in builds with the server (CWLOC_WITH_SERVE).
  [ -x "$build/bin/cwloc-fuzz-serve-request" ] && targets+=(serve_request)
fi
out="${out:-$build/fuzz-runs}"
mkdir -p "$out"

run_target() {  # writes $out/$1.log; the corpus grows in $out/$1.corpus, the seeds stay as they are
  local target="$1" binary="$build/bin/cwloc-fuzz-${1//_/-}"
  mkdir -p "$out/$target.corpus"
  "$binary" -max_total_time="$seconds" -runs="$runs" -timeout=20 -rss_limit_mb=3072 \
    -print_final_stats=1 -artifact_prefix="$out/$target-" \
    "$out/$target.corpus" "fuzz/corpus/$target" >"$out/$target.log" 2>&1
}

pids=() names=()
status=0
for target in "${targets[@]}"; do
  [ -d "fuzz/corpus/$target" ] || { echo "fuzz/run.sh: unknown target '$target'" >&2; exit 2; }
  run_target "$target" &
  pids+=($!) names+=("$target")
  if [ ${#pids[@]} -ge "$jobs" ]; then
    wait "${pids[0]}" || true
    pids=("${pids[@]:1}")
  fi
done
for pid in "${pids[@]}"; do wait "$pid" || true; done

printf '%-16s %14s %8s %10s %8s  %s\n' target executions seconds exec/s corpus outcome
for target in "${names[@]}"; do
  log="$out/$target.log"
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  took=$(sed -n 's/^Done [0-9]* runs in \([0-9]*\) second.*/\1/p' "$log" | tail -1)
  corpus=$(find "$out/$target.corpus" -type f | wc -l)
  artifact=$(ls "$out/$target"-{crash,leak,timeout,oom,slow-unit}-* 2>/dev/null | head -1 || true)
  if [ -n "$artifact" ] || ! grep -q '^Done ' "$log"; then
    outcome="FOUND: ${artifact:-see $log}"
    status=1
  else
    outcome=ok
  fi
  rate=$(( ${execs:-0} / ( ${took:-0} > 0 ? ${took:-1} : 1 ) ))
  printf '%-16s %14s %8s %10s %8s  %s\n' "$target" "${execs:-?}" "${took:-?}" "$rate" "$corpus" "$outcome"
done
if [ "$status" -ne 0 ]; then
  for target in "${names[@]}"; do
    grep -q '^Done ' "$out/$target.log" || { echo "== $target"; tail -60 "$out/$target.log"; }
  done
fi
exit "$status"
