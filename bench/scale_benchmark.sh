#!/usr/bin/env bash
# Scale benchmark: how index build, index size, open time, localizer memory and time per query
# grow with the model, on generated cities of increasing size (docs/benchmarks.md, "Scale").
#
#   bench/scale_benchmark.sh WORKDIR [--sizes 300000,1000000,3000000,10000000] [--queries 50]
#
# For each size S (cwloc-synth --views, so the real view count is within ~10 % of S):
#   WORKDIR/city_S          the city; generated only when missing, so reruns reuse it
#   WORKDIR/index_S.cwl     the index, rebuilt on every run (its build is measured)
#   WORKDIR/results_S.jsonl cluster-wise localization of the city's queries, 1 thread
#   WORKDIR/eval_S.json     cwloc-eval --json of those results
#   WORKDIR/raw_S/          the raw measurements (/usr/bin/time, info, open bench, logs)
# and at the end WORKDIR/scale.tsv, WORKDIR/scale.md (the table printed at the end) and
# WORKDIR/scale.png (cwloc-plot scale: time per query by stage against views).
# Binaries come from $CWLOC_BIN (default: build/bin of this checkout).
set -euo pipefail
top="$(cd "$(dirname "$0")/.." && pwd)"
bin="${CWLOC_BIN:-$top/build/bin}"
python=/usr/bin/python3
me="scale_benchmark.sh"

die() { echo "$me: error: $*" >&2; exit 1; }
usage() { echo "usage: $me WORKDIR [--sizes 300000,1000000,3000000,10000000] [--queries 50]" >&2; exit 2; }

[ $# -ge 1 ] || usage
work="$1"
shift
sizes="300000,1000000,3000000,10000000"
queries=50
while [ $# -gt 0 ]; do
  case "$1" in
    --sizes) [ $# -ge 2 ] || usage; sizes="$2"; shift 2 ;;
    --queries) [ $# -ge 2 ] || usage; queries="$2"; shift 2 ;;
    *) usage ;;
  esac
done
[[ "$sizes" =~ ^[0-9]+(,[0-9]+)*$ ]] || die "--sizes '$sizes': expected comma-separated view counts"
[[ "$queries" =~ ^[1-9][0-9]*$ ]] || die "--queries '$queries': expected a positive number"
for tool in cwloc-synth cwloc-index cwloc-open-bench cwloc-localize cwloc-eval cwloc-plot; do
  [ -x "$bin/$tool" ] || die "$bin/$tool not found (build first, or set CWLOC_BIN)"
done
[ -x /usr/bin/time ] || die "/usr/bin/time not found (Debian: apt-get install time)"
[ -x "$python" ] || die "$python not found"
mkdir -p "$work" || die "cannot create $work"
work="$(cd "$work" && pwd)"

# step NAME RAW_DIR COMMAND...: runs COMMAND under /usr/bin/time (wall seconds and peak RSS in
# RAW_DIR/NAME.time), its stdout in RAW_DIR/NAME.out and stderr in RAW_DIR/NAME.err, and stops
# the benchmark with the step's name and log when it fails. ALLOW_STATUS=1 also accepts exit 1
# (cwloc-localize's "some query was not localized", a result here, not a failure).
step() {
  local name="$1" raw="$2" status=0
  shift 2
  /usr/bin/time -f "%e %M" -o "$raw/$name.time" "$@" >"$raw/$name.out" 2>"$raw/$name.err" || status=$?
  if [ "$status" -gt "${ALLOW_STATUS:-0}" ]; then
    tail -n 5 "$raw/$name.err" >&2
    die "$name failed (exit $status): $*; see $raw/$name.err"
  fi
}

# json FILE EXPR: one value from a JSON file (EXPR is a Python expression on d).
json() { "$python" -c 'import json, sys; d = json.load(open(sys.argv[1])); print(eval(sys.argv[2]))' "$1" "$2"; }

points=()
for s in ${sizes//,/ }; do
  city="$work/city_$s"
  raw="$work/raw_$s"
  index="$work/index_$s.cwl"
  rm -rf "$raw"
  mkdir -p "$raw"
  echo "## $s views: $(uptime)"

  if [ ! -d "$city" ]; then
    # cwloc-synth writes into a temporary directory and renames it at the end, so an existing
    # city_S is always complete.
    echo "   generating $city (cwloc-synth --views $s --queries $queries)"
    step synth "$raw" "$bin/cwloc-synth" -o "$city" --views "$s" --queries "$queries"
  else
    # A reused city (or a symlink to one) must have the knobs this script would generate it
    # with (the others are cwloc-synth's defaults unless someone generated it by hand).
    [ -f "$city/stats.json" ] || die "$city exists but has no stats.json: not a cwloc-synth city"
    knobs="$(json "$city/stats.json" 'd["knobs"]["views_target"], d["knobs"]["queries"], d["seed"]')"
    [ "$knobs" = "($s, $queries, 1)" ] ||
      die "$city was generated with (views, queries, seed) = $knobs, not ($s, $queries, 1); remove it or pass --queries to match"
    echo "   reusing $city"
  fi

  # Build from a warm page cache, as right after generation: otherwise a reused city's build
  # time would include reading the database from disk.
  cat "$city/database.db" >/dev/null
  echo "   building $index"
  step build "$raw" "$bin/cwloc-index" build --model "$city/mapping_model/bin" \
    --database "$city/database.db" -o "$index" --json
  step info "$raw" "$bin/cwloc-index" info --json "$index"
  step verify "$raw" "$bin/cwloc-index" verify "$index"
  step open "$raw" "$bin/cwloc-open-bench" "$index" 200

  echo "   localizing $(grep -vc '^#' "$city/queries_with_intrinsics.txt") queries (1 thread)"
  cat /proc/loadavg >"$raw/localize.loadavg"
  ALLOW_STATUS=1 step localize "$raw" "$bin/cwloc-localize" --index "$index" \
    --database "$city/database.db" --query-list "$city/queries_with_intrinsics.txt" \
    --threads 1 -q -o "$work/results_$s.jsonl"

  step eval "$raw" "$bin/cwloc-eval" --results "$work/results_$s.jsonl" --label "cluster-wise" \
    --gt "$city/queries_gt.txt" --scale "$city/scale_to_metres.txt" \
    --model "$city/mapping_model/bin" --gt-points "$city/queries_gt_points.txt" --json
  cp "$raw/eval.out" "$work/eval_$s.json"

  # The x axis is the index's real view count, not the --views target.
  views="$(json "$raw/info.out" 'd["manifest"]["counts"]["views"]')"
  points+=(--point "$views:$work/eval_$s.json")
done

echo "## plotting $work/scale.png"
"$bin/cwloc-plot" scale "${points[@]}" -o "$work/scale.png" >"$work/scale_plot.txt" ||
  die "cwloc-plot scale failed (see the message above)"

# One table from the raw measurements: printed, and written as scale.tsv and scale.md.
"$python" - "$work" "$sizes" <<'EOF'
import json, math, os, sys

work, sizes = sys.argv[1], [int(s) for s in sys.argv[2].split(",")]
STAGES = ["forward_knn", "ratio_test", "query_tree", "back_matching", "pose"]

def load(path):
    with open(path) as f:
        return json.load(f)

def timed(raw, name):
    """(wall s, peak MB) from /usr/bin/time -f '%e %M' (KiB); its last line, after any exit note."""
    wall, kib = open(os.path.join(raw, name + ".time")).read().split("\n")[-2].split()
    return float(wall), int(kib) * 1024 / 1e6

def open_median_ms(raw):
    """cwloc-open-bench prints a markdown table; the median is the 4th cell of its last row."""
    return float(open(os.path.join(raw, "open.out")).read().strip().splitlines()[-1].split("|")[4])

rows = []
for s in sizes:
    raw = os.path.join(work, f"raw_{s}")
    info = load(os.path.join(raw, "info.out"))
    build = load(os.path.join(raw, "build.out"))["seconds"]
    run = load(os.path.join(work, f"eval_{s}.json"))["runs"][0]
    counts = info["manifest"]["counts"]
    t = run["times_ms"]
    gen = timed(raw, "synth")[0] if os.path.exists(os.path.join(raw, "synth.time")) else None
    rows.append({
        "size": s, "views": counts["views"], "images": counts["images"], "points": counts["points"],
        "gen_s": gen, "build_s": timed(raw, "build")[0], "build_peak_mb": timed(raw, "build")[1],
        "index_mb": info["file_bytes"] / 1e6, "bytes_per_view": info["file_bytes"] / counts["views"],
        **{f"build_{k}_s": v for k, v in build.items() if k != "total"},
        "verify_s": timed(raw, "verify")[0], "open_ms": open_median_ms(raw),
        "localize_peak_mb": timed(raw, "localize")[1],
        "localized": run["localized"], "queries": run["queries"], "share": run["localized_share"],
        "recognition_top1": run["recognition"]["top"]["top1"]["share"],
        "position_error_median_m": run["position_error"]["median"] if run["position_error"] else None,
        "median_ms": t["total"]["median"], "p90_ms": t["total"]["p90"],
        **{f"{st}_ms": t[st]["median"] for st in STAGES},
        "load": float(open(os.path.join(raw, "localize.loadavg")).read().split()[0]),
    })

def f(x, digits=1):
    return "-" if x is None else f"{x:,.{digits}f}"

header = ["views", "images", "build s", "build peak MB", "index MB", "B/view", "open ms",
          "localize peak MB", "localized", "median ms", "p90 ms",
          "median per stage: fwd kNN / ratio / query tree / back-match / pose (ms)"]
table = [[f"{r['views']:,}", f"{r['images']:,}", f(r["build_s"]), f(r["build_peak_mb"], 0),
          f(r["index_mb"]), f(r["bytes_per_view"]), f(r["open_ms"], 4), f(r["localize_peak_mb"], 0),
          f"{r['localized']}/{r['queries']} ({100 * r['share']:.0f} %)", f(r["median_ms"]), f(r["p90_ms"]),
          " / ".join(f"{r[st + '_ms']:.2f}" for st in STAGES)] for r in rows]

# Readable fixed-width table on stdout.
widths = [max(len(row[i]) for row in [header] + table) for i in range(len(header))]
for row in [header] + table:
    print("  ".join(c.rjust(w) if i < len(row) - 1 else c for i, (c, w) in enumerate(zip(row, widths))))

# Growth exponent per stage, the same least-squares slope cwloc-plot gives for the total.
def slope(xs, ys):
    if len(set(xs)) < 2 or min(ys) <= 0:
        return None
    lx, ly = [math.log(x) for x in xs], [math.log(y) for y in ys]
    mx, my = sum(lx) / len(lx), sum(ly) / len(ly)
    return sum((a - mx) * (b - my) for a, b in zip(lx, ly)) / sum((a - mx) ** 2 for a in lx)
views = [r["views"] for r in rows]
exps = {st: slope(views, [r[st + "_ms"] for r in rows]) for st in STAGES + ["median", "p90"]}
exp_line = ", ".join(f"{st} {'-' if e is None else f'{e:.2f}'}" for st, e in exps.items())
plot = open(os.path.join(work, "scale_plot.txt")).read()
growth = next((l for l in plot.splitlines() if l.startswith("growth exponent")), "growth exponent: -")
print(growth)
print("per-stage exponents (median): " + exp_line)

keys = list(rows[0].keys())
with open(os.path.join(work, "scale.tsv"), "w") as out:
    out.write("\t".join(keys) + "\n")
    for r in rows:
        out.write("\t".join("" if r[k] is None else str(round(r[k], 4)) for k in keys) + "\n")

with open(os.path.join(work, "scale.md"), "w") as out:
    out.write("| " + " | ".join(header) + " |\n|" + "---|" * len(header) + "\n")
    for row in table:
        out.write("| " + " | ".join(row) + " |\n")
    out.write(f"\n{growth}\n\nGrowth exponents per stage (median ms ~ views^b): {exp_line}.\n")
    gens = ", ".join(f"{r['views']:,} views {f(r['gen_s'])} s" for r in rows if r["gen_s"] is not None)
    out.write(f"\nCity generation (not part of the table): {gens or 'all cities reused'}. "
              "1-minute load average when localizing: "
              + ", ".join(f"{r['load']:.1f}" for r in rows) + ".\n")
print(f"wrote {work}/scale.tsv, {work}/scale.md, {work}/scale.png")
EOF
