#!/usr/bin/env bash
# Compact index trade-off (issue #26): for each data set, build the full index and compact ones
# of every code size (--compact --code-bytes N), localize the queries with each on one thread
# (photos when the data set has query_images/, else the database's query features), and print
# bytes per view against localized share, median position error and time, each as a ratio to
# the full index.
#
#   bench/compact_benchmark.sh WORKDIR DATASET...
#   CODE_BYTES="64 32 16 8" ROUNDS=3 bench/compact_benchmark.sh /tmp/compact \
#       ../shared/data/herz_jesu_p25 ../shared/data/sceaux_castle /tmp/paper/city
#
# A DATASET is a folder with mapping_model/bin, database.db, queries_with_intrinsics.txt,
# queries_gt.txt and scale_to_metres.txt (the shared data sets and cwloc-synth cities). Indexes
# are rebuilt only when missing. Writes WORKDIR/table.md, WORKDIR/tradeoff.json and the
# figure WORKDIR/compact.png (`cwloc-plot compact`, from each run's cwloc-eval report).
set -euo pipefail
top="$(cd "$(dirname "$0")/.." && pwd)"
bin="${CWLOC_BIN:-$top/build/bin}"
codes="${CODE_BYTES:-64 32 16 8}"
rounds="${ROUNDS:-3}"
work="$1"
shift
mkdir -p "$work"

for data in "$@"; do
  name="$(basename "$data")"
  [ "$name" = city ] && name="$(basename "$(dirname "$data")")"
  for code in 0 $codes; do
    index="$work/$name-$code.cwl"
    extra=""
    [ "$code" != 0 ] && extra="--compact --code-bytes $code"
    if [ ! -f "$index" ]; then
      echo "## $name: building the index (code bytes $code)" >&2
      start=$(date +%s%N)
      # shellcheck disable=SC2086
      "$bin/cwloc-index" build --model "$data/mapping_model/bin" --database "$data/database.db" \
        -o "$index" $extra >&2
      echo "$((($(date +%s%N) - start) / 1000000))e-3" >"$index.build_seconds"
    fi
  done
  "$top/bench/reload_index.py" "$work/$name"-*.cwl
  if [ -d "$data/query_images" ]; then
    queries=(--image-list "$data/queries_with_intrinsics.txt" --image-dir "$data/query_images")
  else
    queries=(--database "$data/database.db" --query-list "$data/queries_with_intrinsics.txt")
  fi
  rm -f "$work/$name"-*.jsonl "$work/$name"-*.rss
  for ((round = 1; round <= rounds; round++)); do
    for code in 0 $codes; do
      echo "## $name: round $round, code bytes $code" >&2
      status=0
      /usr/bin/time -f "%M" -a -o "$work/$name-$code.rss" "$bin/cwloc-localize" \
        --index "$work/$name-$code.cwl" "${queries[@]}" --threads 1 -q \
        -o "$work/$name-$code.round$round.jsonl" || status=$?
      [ "$status" -le 1 ] || exit "$status"
    done
  done
  echo "$data" >"$work/$name.dataset"
done

python3 - "$work" "$bin" "$codes" "$@" <<'PY'
import json, os, statistics, subprocess, sys
work, bin_dir, codes = sys.argv[1], sys.argv[2], ["0"] + sys.argv[3].split()
rows = []
for data in sys.argv[4:]:
    name = os.path.basename(data.rstrip("/"))
    if name == "city":
        name = os.path.basename(os.path.dirname(data.rstrip("/")))
    full = None
    for code in codes:
        base = f"{work}/{name}-{code}"
        info = json.loads(subprocess.run([f"{bin_dir}/cwloc-index", "info", "--json", base + ".cwl"],
                                         capture_output=True, text=True, check=True).stdout)
        rounds = sorted(f for f in os.listdir(work) if f.startswith(f"{name}-{code}.round"))
        records = [json.loads(line) for f in rounds for line in open(f"{work}/{f}")]
        first = f"{work}/{rounds[0]}"
        report_text = subprocess.run(
            [f"{bin_dir}/cwloc-eval", "--results", first, "--gt", f"{data}/queries_gt.txt",
             "--scale", f"{data}/scale_to_metres.txt", "--json"],
            capture_output=True, text=True, check=True).stdout
        open(base + ".eval.json", "w").write(report_text)
        report = json.loads(report_text)["runs"][0]
        after_extraction = [r["times_ms"]["total"] - r["times_ms"]["extraction"] for r in records]
        rss = [int(line) / 1024 for line in open(base + ".rss") if line.strip().isdigit()]
        row = {
            "data_set": name, "code_bytes": int(code),
            "bytes_per_view": info["bytes_per_view"], "file_mb": info["file_bytes"] / 1e6,
            "build_s": float(open(base + ".cwl.build_seconds").read()),
            "queries": report["queries"], "localized": report["localized"],
            "median_error_m": (report["position_error"] or {}).get("median"),
            "median_ms": statistics.median(after_extraction),
            "peak_rss_mb": statistics.median(rss),
        }
        if full is None:
            full = row
        row["error_ratio"] = (row["median_error_m"] / full["median_error_m"]
                              if row["median_error_m"] and full["median_error_m"] else None)
        row["time_ratio"] = row["median_ms"] / full["median_ms"]
        rows.append(row)
json.dump(rows, open(f"{work}/tradeoff.json", "w"), indent=1)
fmt = lambda v, f: "-" if v is None else format(v, f)
lines = ["| data set | index | bytes / view | MB | build s | localized | median error (m) | "
         "vs full | ms / query (median, after extraction) | vs full | peak RSS MB |",
         "|---|---|---|---|---|---|---|---|---|---|---|"]
for r in rows:
    label = "full" if r["code_bytes"] == 0 else f"compact, {r['code_bytes']} B codes"
    lines.append(f"| {r['data_set']} | {label} | {r['bytes_per_view']:.1f} | {r['file_mb']:.1f} | "
                 f"{r['build_s']:.1f} | {r['localized']}/{r['queries']} | "
                 f"{fmt(r['median_error_m'], '.4f')} | {fmt(r['error_ratio'], '.2f')} | "
                 f"{r['median_ms']:.2f} | {r['time_ratio']:.2f} | {r['peak_rss_mb']:.0f} |")
open(f"{work}/table.md", "w").write("\n".join(lines) + "\n")
print("\n".join(lines))
points = []
for r in rows:
    points += ["--point", f"{r['data_set']}:{r['bytes_per_view']:.2f}:"
               f"{work}/{r['data_set']}-{r['code_bytes']}.eval.json"]
subprocess.run([f"{bin_dir}/cwloc-plot", "compact", *points, "-o", f"{work}/compact.png"],
               check=True, stdout=subprocess.DEVNULL)
PY
