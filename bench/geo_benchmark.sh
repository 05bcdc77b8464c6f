#!/usr/bin/env bash
# Geo benchmark: the paper's hard case (strong global repetition) on the globe. A generated city
# at a known WGS84 position with noisy GPS for the mapping images (georef.txt, 10 % outliers)
# and per-query position and gravity priors (query_priors.txt), to measure what the priors buy
# the localizer (docs/synth.md, "On the globe"; docs/benchmarks.md).
#
#   bench/geo_benchmark.sh BUILD_DIR [WORKDIR]
#   bench/geo_benchmark.sh build /tmp/geo
#
# WORKDIR (default BUILD_DIR/geo_benchmark) gets city/, generated only when missing. The
# environment can shrink the city for a quick try: GEO_BENCH_VIEWS (default 300000) and
# GEO_BENCH_QUERIES (default 100).
#
# Then: the index georeferenced by georef.txt, localization without priors, with the GPS prior,
# with the gravity prior and with both, and cwloc-eval on the ground and on the globe.
set -euo pipefail
me="geo_benchmark.sh"
die() { echo "$me: error: $*" >&2; exit 1; }
if [ $# -lt 1 ] || [ $# -gt 2 ]; then
  echo "usage: $me BUILD_DIR [WORKDIR]" >&2
  exit 2
fi
build="$(cd "$1" 2>/dev/null && pwd)" || die "build directory '$1' not found"
bin="$build/bin"
work="${2:-$build/geo_benchmark}"
python=/usr/bin/python3
[ -x "$bin/cwloc-synth" ] || die "$bin/cwloc-synth not found (build the cwloc_synth_exe target)"

# Zurich main station, on the ground: 47.3779 N, 8.5403 E, 455 m above the WGS84 ellipsoid
# (408 m above sea level plus the geoid's 47 m).
geo="47.3779 8.5403 455"
views="${GEO_BENCH_VIEWS:-300000}"
queries="${GEO_BENCH_QUERIES:-100}"
# The hard case of docs/benchmarks.md: 60 % of the facade points repeat 64 motifs city-wide.
city_knobs=(--views "$views" --queries "$queries" --repetition "${GEO_BENCH_REPETITION:-0.6}"
  --motifs "${GEO_BENCH_MOTIFS:-64}" --seed 1)
geo_knobs=(--geo "$geo" --gps-noise 3 --gps-outliers 0.1 --prior-position-error 10
  --prior-radius 50 --prior-gravity-error 1)
city="$work/city"
timing() { /usr/bin/time -f "%e s wall, %M KB peak" "$@"; }

mkdir -p "$work"
if [ ! -d "$city" ]; then
  echo "## generating the city: cwloc-synth ${city_knobs[*]} --geo \"$geo\" ${geo_knobs[*]:2}"
  timing "$bin/cwloc-synth" -o "$city" "${city_knobs[@]}" "${geo_knobs[@]}"
else
  echo "## reusing $city (delete it to regenerate)"
fi

echo "## checking the geo files"
"$python" - "$city" <<'EOF'
import json, pathlib, sys
city = pathlib.Path(sys.argv[1])
def records(name):
    return [l.split() for l in (city / name).read_text().splitlines() if l and not l.startswith("#")]
stats = json.loads((city / "stats.json").read_text())
geo = stats.get("geo")
if geo is None:
    sys.exit(f"{city}: made without --geo (no 'geo' in stats.json); delete it and rerun")
images, queries = stats["counts"]["mapping_images"], stats["counts"]["queries"]
georef, outliers = records("georef.txt"), records("georef_outliers.txt")
priors = records("query_priors.txt")
assert len(georef) == images, (len(georef), images)
assert len(outliers) == geo["gps_outlier_images"] == round(geo["gps_outliers"] * images)
assert len(records("queries_geo.txt")) == queries
assert sum(r[1] == "position" for r in priors) == queries
assert sum(r[1] == "gravity" for r in priors) == queries
o = geo["origin"]
print(f"city at {o['latitude_deg']} {o['longitude_deg']} {o['height_m']} m: {images} mapping "
      f"images ({len(outliers)} GPS outliers), {queries} queries with priors; "
      f"{stats['counts']['views']} views")
EOF

index="$work/city.cwl"
if [ ! -f "$index" ]; then
  echo "## building the index, georeferenced by the noisy GPS positions"
  timing "$bin/cwloc-index" build --model "$city/mapping_model/bin" \
    --database "$city/database.db" --georef "$city/georef.txt" -o "$index"
fi

echo "## the georeference against the truth"
"$bin/cwloc-index" info --json "$index" >"$work/index_info.json"
"$python" - "$work/index_info.json" "$city/georef_outliers.txt" <<'EOF'
import json, sys
fit = json.load(open(sys.argv[1]))["manifest"]["georeference"]["fit"]
flagged = {o["image"] for o in fit["outliers"]}
wild = {l.strip() for l in open(sys.argv[2]) if l.strip()}
print(f"fit: {fit['inliers']} of {fit['observations']} positions kept, rms residual "
      f"{fit['rms_residual_m']:.2f} m (3 m per axis: 3 sqrt(3) = 5.20 m expected); "
      f"{len(flagged)} flagged: {len(flagged & wild)} of the {len(wild)} wild ones, "
      f"{len(flagged - wild)} good ones")
EOF

# Priors files: the position lines, the gravity lines, both.
grep ' position ' "$city/query_priors.txt" >"$work/priors_position.txt"
grep ' gravity ' "$city/query_priors.txt" >"$work/priors_gravity.txt"
cp "$city/query_priors.txt" "$work/priors_both.txt"

# Without priors, with the GPS prior, the gravity prior and both; then without and with the
# gravity prior under RANSAC's adaptive stopping alone (--min-ransac-iterations 0): with
# COLMAP's minimum of 100 hypotheses, the clean correspondences of the cluster-wise matcher stop
# every run at that floor. Rounds alternate the runs so that a shared machine's load falls on
# all of them alike.
runs=(default.none default.position default.gravity default.both adaptive.none adaptive.gravity)
rounds="${GEO_BENCH_ROUNDS:-3}"
for round in $(seq 1 "$rounds"); do
  for run in "${runs[@]}"; do
    setting="${run%.*}" prior="${run#*.}"
    extra=()
    [ "$prior" = none ] || extra+=(--priors "$work/priors_$prior.txt")
    [ "$setting" = adaptive ] && extra+=(--min-ransac-iterations 0)
    echo "## round $round: $setting RANSAC, priors: $prior (1 thread)"
    status=0
    "$bin/cwloc-localize" --index "$index" --database "$city/database.db" \
      --query-list "$city/queries_with_intrinsics.txt" --threads 1 -q \
      "${extra[@]}" -o "$work/results_${run}_$round.jsonl" || status=$?
    [ "$status" -le 1 ] || exit "$status"
  done
done
for run in "${runs[@]}"; do cp "$work/results_${run}_1.jsonl" "$work/results_$run.jsonl"; done

echo "## evaluation"
results=()
for run in "${runs[@]}"; do results+=(--results "$work/results_$run.jsonl" --label "$run"); done
"$bin/cwloc-eval" "${results[@]}" --gt "$city/queries_gt.txt" --index "$index" \
  --gt-geo "$city/queries_geo.txt"

echo "## per run (docs/benchmarks.md, \"Priors\")"
"$python" - "$work" "$rounds" "${runs[@]}" <<'EOF'
import json, statistics, sys
work, rounds, runs = sys.argv[1], int(sys.argv[2]), sys.argv[3:]
def load(run, k):
    return {j["name"]: j for j in map(json.loads, open(f"{work}/results_{run}_{k}.jsonl"))}
first = {r: load(r, 1) for r in runs}
print("| RANSAC, priors | localized | batch s | total ms | back-matching ms | pose ms "
      "| back-matched clusters | RANSAC iterations: mean, p90, max |")
print("|---|---|---|---|---|---|---|---|")
for r in runs:
    d = first[r]
    setting = r.split(".")[0]
    # The queries every run of this setting localized.
    common = set.intersection(*({n for n, j in first[o].items() if j.get("success")}
                                for o in runs if o.startswith(setting + ".")))
    # Times: per round the median over the common queries, then the median over rounds.
    def ms(stage):
        return statistics.median(
            statistics.median(load(r, k)[n]["times_ms"][stage] for n in common)
            for k in range(1, rounds + 1))
    # The whole batch, failures included: what a user waits for.
    batch = statistics.median(sum(j["times_ms"]["total"] for j in load(r, k).values()) / 1e3
                              for k in range(1, rounds + 1))
    its = sorted(d[n]["matches"]["ransac_iterations"] for n in common)
    clusters = statistics.median(d[n]["matches"]["back_matched_images"] for n in common)
    print(f"| {r.replace('.', ', ')} | {sum(bool(j.get('success')) for j in d.values())}/{len(d)} "
          f"| {batch:.2f} | {ms('total'):.2f} | {ms('back_matching'):.2f} | {ms('pose'):.3f} | {clusters:.0f} "
          f"| {statistics.mean(its):.0f}, {its[int(0.9 * (len(its) - 1))]}, {its[-1]} |")
print(f"(times: medians over the queries every run of the setting localized, then over "
      f"{rounds} rounds; iterations over the same queries, first round)")
EOF
