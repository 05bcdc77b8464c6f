#!/usr/bin/env bash
# Two builds give the same outputs, for a change that should not change any answer (#64: every
# output byte-identical on herz_jesu_p25, sceaux_castle, fox_video and the demo city). Each build
# makes, in a folder of its own and under the same relative names (so paths inside the files
# agree), then the two folders are compared file by file:
# - indexes (full and --compact) of the three real sets' mapping models and of the demo city,
#   and `cwloc-index info --json` of each;
# - updates to the full models (`update --delta`) and the delta applied (`apply`), compact too;
#   tiles (`extract --images`, and `--near` on a georeferenced city), and a tile's share of an
#   update (`extract --parent-tile --delta`) applied;
# - cwloc-localize's JSON records, pose lines and exit codes: every set's database queries on
#   both indexes, its photos at the database's SIFT settings (two threads: compared in name
#   order), a photo at the defaults; fox_video's
#   queries as a `--sequence` (trajectories: TUM, LaMAR) and a clip of its frames as `--video`
#   (kapture); herz_jesu's queries as `--frames` (known and unknown scale); a synthetic rig city
#   (`--geo --rig-cameras 2`) with `--rig`, and its tile with `--priors`;
# - cwloc-synth's files (its stats.json without times, memory and output path).
# JSON records are compared without IGNORE_KEYS (default "times_ms tracking.time_ms": a key, or
# PARENT.KEY, dropped at any depth; add one a change renames on purpose), everything else byte
# for byte. Prints one line per comparison; exits 1 when anything differs or is missing.
# Usage: tools/check_same_outputs.sh OLD_BIN_DIR NEW_BIN_DIR OUT_DIR (bin folders with
# cwloc-index, cwloc-localize and cwloc-synth). The two builds run at once: 4 min on 2 cores
# shared with other builds (load 7-8); ffmpeg makes the clip once for both. Each step's time
# is in OUT/old.log and OUT/new.log.
set -euo pipefail
[ $# -eq 3 ] || { echo "usage: $0 OLD_BIN_DIR NEW_BIN_DIR OUT_DIR" >&2; exit 2; }
old=$(cd "$1" && pwd) new=$(cd "$2" && pwd)
mkdir -p "$3"
out=$(cd "$3" && pwd)
data="$(cd "$(dirname "$0")/../.." && pwd)/shared/data"
export IGNORE_KEYS=${IGNORE_KEYS:-times_ms tracking.time_ms}
sets="herz_jesu_p25 sceaux_castle fox_video"
for set in $sets; do [ -d "$data/$set" ] || { echo "missing $data/$set" >&2; exit 2; }; done
command -v ffmpeg >/dev/null || { echo "needs ffmpeg (tools/install-deps.sh)" >&2; exit 2; }
start=$SECONDS

# Inputs both builds read, made here once.
rm -rf "$out/old" "$out/new" "$out/inputs"
mkdir -p "$out/inputs" "$out/old" "$out/new"
fox=$data/fox_video
# A clip of fox_video's first 6 query frames at half size, 2 per second (as video_cli_test.cc).
for i in 0 1 2 3 4 5; do
  ln -s "$fox/query_images/$(sed -n "$((i + 1))p" "$fox/query_list.txt")" "$out/inputs/00$i.jpg"
done
ffmpeg -loglevel error -y -framerate 2 -i "$out/inputs/%03d.jpg" -vf scale=540:960 -c:v libx264 \
  -pix_fmt yuv420p -movflags +faststart "$out/inputs/fox.mp4"
# herz_jesu's queries as two --frames frames, each image's cam_from_rig from the ground truth
# (cam_from_world of the image times world_from_cam of the frame's first), and the same with the
# translations scaled by 3.7 for --frames-scale unknown (as rig_cli_test.cc).
python3 - "$data/herz_jesu_p25/queries_gt.txt" "$out/inputs" <<'EOF'
import sys
def mul(a, b):
    return (a[0]*b[0]-a[1]*b[1]-a[2]*b[2]-a[3]*b[3], a[0]*b[1]+a[1]*b[0]+a[2]*b[3]-a[3]*b[2],
            a[0]*b[2]-a[1]*b[3]+a[2]*b[0]+a[3]*b[1], a[0]*b[3]+a[1]*b[2]-a[2]*b[1]+a[3]*b[0])
def rotate(q, v):
    r = mul(mul(q, (0.0,) + tuple(v)), (q[0], -q[1], -q[2], -q[3]))
    return r[1:]
gt = {}
for line in open(sys.argv[1]):
    f = line.split()
    if f and not f[0].startswith('#'):
        gt[f[0]] = ([float(x) for x in f[1:5]], [float(x) for x in f[5:8]], ' '.join(f[8:]))
for name, scale in (('herz_frames.txt', 1.0), ('herz_frames_scaled.txt', 3.7)):
    with open(f'{sys.argv[2]}/{name}', 'w') as out:
        for g, frame in enumerate((('0002.jpg', '0007.jpg'), ('0012.jpg', '0017.jpg', '0022.jpg'))):
            q0, t0, _ = gt[frame[0]]
            for image in frame:
                q, t, camera = gt[image]
                q_rel = mul(q, (q0[0], -q0[1], -q0[2], -q0[3]))
                t_rel = [scale * (a - b) for a, b in zip(t, rotate(q_rel, t0))]
                print(f'frame{g} {image}', *('%.17g' % x for x in q_rel + tuple(t_rel)), camera,
                      file=out)
EOF
# herz_jesu's tile: the clusters (images) 0000-0010 of its mapping model.
printf '%s\n' 0000.jpg 0001.jpg 0003.jpg 0004.jpg 0005.jpg 0006.jpg 0008.jpg 0009.jpg 0010.jpg \
  >"$out/inputs/herz_tile_images.txt"

produce() {  # BIN: every output of one build, in the current folder
  local bin=$1
  index() {  # the time each step took goes to the build's log (OUT/old.log, OUT/new.log)
    local t=$SECONDS
    "$bin/cwloc-index" "$@" >>index.log
    echo "$((SECONDS - t)) s: cwloc-index $*"
  }
  info() { "$bin/cwloc-index" info --json "$1.cwl" >"$1.info.json"; }
  localize() {  # NAME ARGS: NAME.jsonl, NAME.poses and NAME.status (exit code: 0, or 1 if some failed)
    local name=$1 status=0 t=$SECONDS
    shift
    "$bin/cwloc-localize" "$@" -q -o "$name.jsonl" --poses "$name.poses" >"$name.log" 2>&1 ||
      status=$?
    echo "$status" >"$name.status"
    echo "$((SECONDS - t)) s: localize $name"
    [ "$status" -le 1 ] || { cat "$name.log"; echo "$name: cwloc-localize exit $status"; return 1; }
  }
  in_name_order() {  # NAME: a batch of several threads writes its records as they finish
    LC_ALL=C sort -o "$1.poses" "$1.poses"
    python3 -c 'import json, sys
lines = open(sys.argv[1]).readlines()
open(sys.argv[1], "w").writelines(sorted(lines, key=lambda l: json.loads(l)["name"]))' "$1.jsonl"
  }
  local set s
  for set in $sets; do
    s=$data/$set
    index build --model "$s/mapping_model/bin" --database "$s/database.db" -o "$set.cwl"
    # The covariance calibration of a compact build trains a codebook per fold (35-75 s a set
    # on a loaded core): the demo city's compact build keeps it, these are the same code without.
    index build --model "$s/mapping_model/bin" --database "$s/database.db" --compact \
      --calibration-samples 0 -o "$set.compact.cwl"
    for kind in "" .compact; do
      info "$set$kind"
      localize "$set$kind.db" --index "$set$kind.cwl" --database "$s/database.db" \
        --query-list "$s/queries_with_intrinsics.txt"
      # The model grew to the full model: the update, its delta, and the delta applied.
      index update --index "$set$kind.cwl" --model "$s/full_model/bin" --database "$s/database.db" \
        -o "$set$kind.updated.cwl" --delta "$set$kind.cwld"
      index apply --index "$set$kind.cwl" --delta "$set$kind.cwld" -o "$set$kind.applied.cwl"
      info "$set$kind.updated"
    done
    localize "$set.photos" --index "$set.cwl" --image-list "$s/query_list.txt" \
      --image-dir "$s/query_images" --max-image-size 1600 --max-features 6000 --threads 2
    in_name_order "$set.photos"
  done
  local h=$data/herz_jesu_p25
  # A photo at the defaults (the 1080 x 1920 frame SIFT doubles, as README's ~440 ms).
  localize fox_video.photo_default --index fox_video.cwl --image "$fox/query_images/0002.jpg"
  localize herz_jesu_p25.frames --index herz_jesu_p25.cwl --database "$h/database.db" \
    --frames ../inputs/herz_frames.txt
  localize herz_jesu_p25.frames_scaled --index herz_jesu_p25.cwl --database "$h/database.db" \
    --frames ../inputs/herz_frames_scaled.txt --frames-scale unknown
  # A tile of herz_jesu, its share of the update to the full model, applied on the device.
  index extract --index herz_jesu_p25.cwl --images ../inputs/herz_tile_images.txt -o herz_tile.cwl
  index extract --index herz_jesu_p25.updated.cwl --parent-tile herz_tile.cwl \
    --delta herz_tile.cwld -o herz_tile.updated.cwl
  index apply --index herz_tile.cwl --delta herz_tile.cwld -o herz_tile.applied.cwl
  info herz_tile
  localize herz_tile.db --index herz_tile.cwl --database "$h/database.db" \
    --query-list "$h/queries_with_intrinsics.txt"
  # fox_video's queries in order as frames of one camera, then its clip.
  localize fox_video.sequence --index fox_video.cwl --database "$fox/database.db" \
    --query-list "$fox/queries_with_intrinsics.txt" --sequence --trajectory fox_video.sequence.tum
  localize fox_video.sequence_lamar --index fox_video.cwl --database "$fox/database.db" \
    --query-list "$fox/queries_with_intrinsics.txt" --sequence \
    --trajectory fox_video.sequence.lamar --trajectory-format lamar
  localize fox_video.video --index fox_video.cwl --video ../inputs/fox.mp4 --threads 2 \
    --camera 'SIMPLE_RADIAL 540 960 692.745 270 480 0.0030128' --first-octave 0 \
    --max-features 2000 --trajectory fox_video.video.kapture --trajectory-format kapture

  # The demo city.
  "$bin/cwloc-synth" --preset demo -o demo_city >synth.log
  index build --model demo_city/mapping_model/bin --database demo_city/database.db -o demo_city.cwl
  index build --model demo_city/mapping_model/bin --database demo_city/database.db --compact \
    -o demo_city.compact.cwl
  for kind in "" .compact; do
    info "demo_city$kind"
    localize "demo_city$kind.db" --index "demo_city$kind.cwl" --database demo_city/database.db \
      --query-list demo_city/queries_with_intrinsics.txt
  done
  # A city on the globe (with GPS outliers) whose queries are rig frames of two cameras: the
  # georeferenced index, a tile near its centre, images removed by an update, the tile's share.
  "$bin/cwloc-synth" --preset demo --geo "48.137154 11.576124 520" --gps-outliers 0.1 \
    --rig-cameras 2 -o geo_city >>synth.log
  index build --model geo_city/mapping_model/bin --database geo_city/database.db \
    --georef geo_city/georef.txt -o geo_city.cwl
  index extract --index geo_city.cwl --near "48.137154 11.576124 30" -o geo_tile.cwl
  grep -v '^#' geo_city/georef.txt | awk 'NR % 10 == 1 { print $1 }' >geo_city.removed.txt
  index update --index geo_city.cwl --model geo_city/mapping_model/bin \
    --database geo_city/database.db --remove-images geo_city.removed.txt \
    -o geo_city.updated.cwl --delta geo_city.cwld
  index apply --index geo_city.cwl --delta geo_city.cwld -o geo_city.applied.cwl
  index extract --index geo_city.updated.cwl --parent-tile geo_tile.cwl --delta geo_tile.cwld \
    -o geo_tile.updated.cwl
  index apply --index geo_tile.cwl --delta geo_tile.cwld -o geo_tile.applied.cwl
  for name in geo_city geo_tile geo_city.updated; do info "$name"; done
  localize geo_city.rig --index geo_city.cwl --database geo_city/database.db \
    --rig geo_city/rig_config.json --query-list geo_city/queries_with_intrinsics.txt
  # The front cameras' images alone: a back camera sometimes sees nothing (no features, exit 2).
  grep '^cam0/' geo_city/queries_with_intrinsics.txt >geo_city.cam0.txt
  localize geo_tile.priors --index geo_tile.cwl --database geo_city/database.db \
    --query-list geo_city.cam0.txt --priors geo_city/query_priors.txt
}

# The two builds at once; a build that fails shows its log.
pids=()
for v in old new; do
  bin=$([ $v = old ] && echo "$old" || echo "$new")
  (cd "$out/$v" && produce "$bin") >"$out/$v.log" 2>&1 &
  pids+=($!)
done
failed=0
for i in 0 1; do
  if ! wait "${pids[$i]}"; then
    v=$([ "$i" = 0 ] && echo old || echo new)
    tail -20 "$out/$v.log"
    echo "the $v build's outputs stopped (the log above, also in $out/$v.log)" >&2
    failed=1
  fi
done
[ "$failed" = 0 ] || exit 1

status=0
python3 - "$out/old" "$out/new" <<'EOF' || status=$?
import filecmp, json, os, sys
old, new = sys.argv[1:3]
ignored = os.environ['IGNORE_KEYS'].split()
def strip(value, parent=''):
    """The value without the ignored keys (KEY anywhere, PARENT.KEY in any object under PARENT)."""
    if isinstance(value, dict):
        return {k: strip(v, k) for k, v in value.items()
                if k not in ignored and f'{parent}.{k}' not in ignored}
    if isinstance(value, list):
        return [strip(v, parent) for v in value]
    return value
def synth_stats(value):  # cwloc-synth's stats.json: its times, memory and absolute output path vary
    return {k: v for k, v in value.items() if k not in ('output', 'timings', 'peak_memory_bytes')}
def lines(path):
    with open(path, 'rb') as f:
        return sum(1 for _ in f)
def files(root):
    return sorted(os.path.relpath(os.path.join(d, f), root) for d, _, names in os.walk(root)
                  for f in names if not f.endswith('.log'))
status = 0
old_files, new_files = files(old), files(new)
for name in sorted(set(old_files) | set(new_files)):
    a, b = os.path.join(old, name), os.path.join(new, name)
    if not os.path.exists(a) or not os.path.exists(b):
        print(f'{name}: DIFFER (only the {"old" if os.path.exists(a) else "new"} build wrote it)')
        status = 1
        continue
    if name.endswith('.jsonl'):
        with open(a) as fa, open(b) as fb:
            ra, rb = [strip(json.loads(l)) for l in fa], [strip(json.loads(l)) for l in fb]
        same, what = ra == rb, f'JSON without {" ".join(ignored)}'
        detail = f' ({len(rb)} records)'
    elif name.endswith('.json'):
        with open(a) as fa, open(b) as fb:
            ra, rb = json.load(fa), json.load(fb)
        if os.path.basename(name) == 'stats.json':
            ra, rb = synth_stats(ra), synth_stats(rb)
        same, what, detail = strip(ra) == strip(rb), 'JSON', ''
    else:
        same, what = filecmp.cmp(a, b, shallow=False), 'bytes'
        detail = f' ({lines(b)} lines)' if name.endswith(('.poses', '.tum', '.kapture', '.lamar')) \
            else f' ({os.path.getsize(b)} bytes)' if name.endswith(('.cwl', '.cwld')) else ''
    print(f'{name}: {what} {"identical" if same else "DIFFER"}{detail}')
    status |= not same
sys.exit(status)
EOF
echo "$(basename "$0"): $([ $status = 0 ] && echo "all identical" || echo "OUTPUTS DIFFER"), $((SECONDS - start)) s"
exit $status
