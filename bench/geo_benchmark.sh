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

runs=(none position gravity both)
for run in "${runs[@]}"; do
  extra=()
  [ "$run" = none ] || extra=(--priors "$work/priors_$run.txt")
  echo "## localizing, priors: $run (1 thread)"
  status=0
  timing "$bin/cwloc-localize" --index "$index" --database "$city/database.db" \
    --query-list "$city/queries_with_intrinsics.txt" --threads 1 -q \
    "${extra[@]}" -o "$work/results_$run.jsonl" || status=$?
  [ "$status" -le 1 ] || exit "$status"
done

echo "## evaluation"
results=()
for run in "${runs[@]}"; do results+=(--results "$work/results_$run.jsonl" --label "$run"); done
"$bin/cwloc-eval" "${results[@]}" --gt "$city/queries_gt.txt" --index "$index" \
  --gt-geo "$city/queries_geo.txt"

echo "## per run: localized, and medians over the queries every run localized"
"$python" - "$work" "${runs[@]}" <<'EOF'
import json, statistics, sys
work, runs = sys.argv[1], sys.argv[2:]
data = {r: {j["name"]: j for j in map(json.loads, open(f"{work}/results_{r}.jsonl"))} for r in runs}
common = set.intersection(*({n for n, j in d.items() if j.get("success")} for d in data.values()))
print("| priors | localized | total ms | pose ms | RANSAC iterations | back-matched clusters |")
print("|---|---|---|---|---|---|")
for r in runs:
    d = data[r]
    med = lambda f: statistics.median(f(d[n]) for n in common)
    print(f"| {r} | {sum(bool(j.get('success')) for j in d.values())}/{len(d)} "
          f"| {med(lambda j: j['times_ms']['total']):.2f} | {med(lambda j: j['times_ms']['pose']):.2f} "
          f"| {med(lambda j: j['matches']['ransac_iterations']):.0f} "
          f"| {med(lambda j: j['matches']['back_matched_images']):.0f} |")
print(f"(medians over the {len(common)} queries every run localized)")
EOF
