#!/usr/bin/env bash
# Sequences of real photos against a map of their neighbours: how many frames the tracker
# tracks, how accurately against each frame localized alone, and how fast (docs/benchmarks.md,
# "Sequences"). Every set's frames are localized alone and as a sequence (--sequence) from
# their stored features and known cameras, then timed by cwloc-sequence-bench (one core).
#
#   bench/sequence_benchmark.sh WORKDIR [SET ...]
#   CWLOC_BIN=/tmp/bin ROUNDS=10 bench/sequence_benchmark.sh /tmp/seq fox_video herz_jesu_p25
#
# SET: a folder name in ../shared/data or a path to a data set (default: fox_video
# herz_jesu_p25:odd). SET alone: its mapping_model/bin and its queries (query_list.txt in time
# order, queries_with_intrinsics.txt, queries_gt.txt), as fox_video ships them. SET:odd: its
# full_model/bin split (herz_jesu_p25's photos are a walk around a church): the odd-numbered
# photos in name order are the frames, the others the map (colmap image_deleter, no
# re-adjustment, so the frames' poses in full_model are their ground truth).
# PHOTO_FLAGS, when set: a set as shipped is localized from its photos (query_images/, each
# frame's camera from queries_with_intrinsics.txt) with these extraction flags ("" for COLMAP's
# settings; "--first-octave 0 --max-image-size 960 --max-features 2000" for the frame settings),
# and the times are the records': a tracked frame's tracking.time_ms against the same frame's
# times_ms.total minus extraction alone.
# VIDEO_FLAGS, when set: as PHOTO_FLAGS, from the set's frames encoded in query_list.txt's order
# into an H.264 video (WORKDIR/NAME/frames.mp4, 2 frames per second, ffmpeg -crf 18) and read
# with --video and the first frame's camera; frame by frame, the video's frames as ffmpeg
# decodes them to grey PNGs. The ground truth is renamed to the video's frame names
# (frames.mp4#INDEX), and the whole frame's time, decoding included, is the run's wall time
# over its frames on one thread.
# Writes WORKDIR/NAME[-odd]/{map,index.cwl,frames.txt,gt.txt,alone.jsonl,sequence.jsonl}.
set -euo pipefail
top="$(cd "$(dirname "$0")/.." && pwd)"
bin="${CWLOC_BIN:-$top/build/bin}"
rounds="${ROUNDS:-5}"
[ $# -ge 1 ] || { echo "usage: $0 WORKDIR [SET ...]" >&2; exit 2; }
work="$(realpath -m "$1")"
shift
sets=("$@")
[ ${#sets[@]} -gt 0 ] || sets=(fox_video herz_jesu_p25:odd)
[ -z "${PHOTO_FLAGS+set}" ] || [ -z "${VIDEO_FLAGS+set}" ] ||
  { echo "$0: PHOTO_FLAGS or VIDEO_FLAGS, not both" >&2; exit 2; }
for tool in cwloc-index cwloc-localize cwloc-eval cwloc-sequence-bench; do
  [ -x "$bin/$tool" ] || { echo "$0: $bin/$tool not found (build first, or set CWLOC_BIN)" >&2; exit 2; }
done
export QT_QPA_PLATFORM=offscreen # colmap is a Qt program; no X server here

for set in "${sets[@]}"; do
  data="${set%:odd}"
  [ -d "$data" ] || data="$top/../shared/data/$data"
  [ -d "$data" ] || { echo "$0: no data set ${set%:odd}" >&2; exit 2; }
  data="$(realpath "$data")"
  name="$(basename "$data")"
  [ "$set" = "${set%:odd}" ] || name="$name-odd"
  out="$work/$name"
  mkdir -p "$out"
  if [ "$set" = "${set%:odd}" ]; then
    for f in mapping_model/bin query_list.txt queries_with_intrinsics.txt queries_gt.txt; do
      [ -e "$data/$f" ] || { echo "$0: $data/$f is missing" >&2; exit 2; }
    done
    model="$data/mapping_model/bin"
    awk 'NR == FNR { camera[$1] = $0; next } NF { print camera[$1] }' \
      "$data/queries_with_intrinsics.txt" "$data/query_list.txt" >"$out/frames.txt"
    cp "$data/queries_gt.txt" "$out/gt.txt"
    split="its own map and queries"
  else
    [ -d "$data/full_model/bin" ] || { echo "$0: $data/full_model/bin is missing" >&2; exit 2; }
    command -v colmap >/dev/null || { echo "$0: colmap not found (needed to split $name)" >&2; exit 2; }
    model="$out/map"
    if [ ! -f "$out/gt.txt" ]; then
      mkdir -p "$out/full_txt" "$model"
      colmap model_converter --input_path "$data/full_model/bin" --output_path "$out/full_txt" \
        --output_type TXT >"$out/full_txt/log" 2>&1
      # Every image's pose and camera (the image line of each pair in images.txt), name order.
      awk 'FNR == 1 { file++ } /^#/ || !NF { next }
           file == 1 { id = $1; $1 = ""; camera[id] = substr($0, 2); next }
           file == 2 && ++line % 2 == 1 { print $10, $2, $3, $4, $5, $6, $7, $8, camera[$9] }' \
        "$out/full_txt/cameras.txt" "$out/full_txt/images.txt" | sort >"$out/all.txt"
      awk 'NR % 2 == 0' "$out/all.txt" >"$out/gt.body"
      awk '{ print $1 }' "$out/gt.body" >"$out/frame_names.txt"
      colmap image_deleter --input_path "$data/full_model/bin" --output_path "$model" \
        --image_names_path "$out/frame_names.txt" >"$out/image_deleter.log" 2>&1
      awk '{ $2 = $3 = $4 = $5 = $6 = $7 = $8 = ""; print }' "$out/gt.body" |
        tr -s ' ' >"$out/frames.txt"
      { echo "# NAME QW QX QY QZ TX TY TZ CAMERA_MODEL WIDTH HEIGHT PARAMS... (full_model)"
        cat "$out/gt.body"; } >"$out/gt.txt"
    fi
    split="its odd-numbered photos against a map of the others"
  fi
  source=(--database "$data/database.db" --query-list "$out/frames.txt")
  if [ -n "${VIDEO_FLAGS+set}" ]; then
    [ "$set" = "${set%:odd}" ] || { echo "$0: VIDEO_FLAGS needs a set as shipped (its query_images/)" >&2; exit 2; }
    command -v ffmpeg >/dev/null || { echo "$0: ffmpeg not found (needed to encode $name)" >&2; exit 2; }
    video="$out/frames.mp4"
    if [ ! -f "$video" ]; then
      rm -rf "$out/video_frames"
      mkdir -p "$out/video_frames"
      awk '{ printf "%s %05d.jpg\n", $1, NR - 1 }' "$out/frames.txt" | while read -r photo frame; do
        ln -s "$data/query_images/$photo" "$out/video_frames/$frame"
      done
      ffmpeg -loglevel error -framerate 2 -i "$out/video_frames/%05d.jpg" -c:v libx264 -crf 18 \
        -pix_fmt yuv420p -f mp4 "$video.part"
      # Its frames as ffmpeg decodes them, for the frame-by-frame run (--video always tracks).
      rm -rf "$out/video_png"
      mkdir -p "$out/video_png"
      ffmpeg -loglevel error -i "$video.part" -pix_fmt gray -start_number 0 "$out/video_png/%05d.png"
      mv "$video.part" "$video"
    fi
    awk '{ $1 = sprintf("%05d.png", NR - 1); print }' "$out/frames.txt" >"$out/video_png.txt"
    # The frames' names in the video, in the ground truth's lines.
    awk -v video="$video" 'NR == FNR { index_of[$1] = FNR - 1; next }
         /^#/ || !NF { print; next } { $1 = video "#" index_of[$1]; print }' \
      "$out/frames.txt" "$data/queries_gt.txt" >"$out/gt.txt"
    camera="$(awk 'NR == 1 { $1 = ""; print substr($0, 2) }' "$out/frames.txt")"
    # shellcheck disable=SC2206
    source=(--image-list "$out/video_png.txt" --image-dir "$out/video_png" $VIDEO_FLAGS)
    # shellcheck disable=SC2206
    sequence=(--video "$video" --camera "$camera" $VIDEO_FLAGS)
    split="$split, as an H.264 video ${VIDEO_FLAGS:-at the COLMAP settings}"
  elif [ -n "${PHOTO_FLAGS+set}" ]; then
    [ "$set" = "${set%:odd}" ] || { echo "$0: PHOTO_FLAGS needs a set as shipped (its query_images/)" >&2; exit 2; }
    # shellcheck disable=SC2206
    source=(--image-list "$out/frames.txt" --image-dir "$data/query_images" $PHOTO_FLAGS)
    split="$split, from its photos ${PHOTO_FLAGS:-at the COLMAP settings}"
  fi
  [ -f "$out/index.cwl" ] ||
    "$bin/cwloc-index" build --model "$model" --database "$data/database.db" -o "$out/index.cwl" >"$out/index.log"
  frames=(--index "$out/index.cwl" "${source[@]}")
  "$bin/cwloc-localize" "${frames[@]}" --threads 1 -q -o "$out/alone.jsonl"
  [ -n "${VIDEO_FLAGS+set}" ] || sequence=("${source[@]}" --sequence)
  start=$(date +%s%N)
  "$bin/cwloc-localize" --index "$out/index.cwl" "${sequence[@]}" --threads 1 -q -o "$out/sequence.jsonl"
  wall_ms=$((($(date +%s%N) - start) / 1000000))
  if [ -n "${VIDEO_FLAGS+set}" ]; then
    # The decoded frames' records under the video's frame names.
    python3 - "$out" "$video" <<'PY'
import json, sys
out, video = sys.argv[1:3]
index_of = {line.split()[0]: i for i, line in enumerate(open(f"{out}/video_png.txt"))}
records = [json.loads(line) for line in open(f"{out}/alone.jsonl")]
with open(f"{out}/alone.jsonl", "w") as f:
    for r in records:
        r["name"] = f"{video}#{index_of[r['name']]}"
        f.write(json.dumps(r) + "\n")
PY
  fi

  echo
  echo "### $name: $(wc -l <"$out/frames.txt") frames, $split"
  "$bin/cwloc-eval" --results "$out/alone.jsonl" --label alone --results "$out/sequence.jsonl" \
    --label sequence --gt "$out/gt.txt" --scale "$data/scale_to_metres.txt"
  python3 - "$out" "$data/scale_to_metres.txt" "${PHOTO_FLAGS+photos}${VIDEO_FLAGS+photos}" \
    "${VIDEO_FLAGS+$wall_ms}" <<'PY'
import json, math, statistics, sys
out = sys.argv[1]
# Metres, as cwloc-eval reports them: the similarity's scale ("scale S" line).
scale = next(float(l.split()[1]) for l in open(sys.argv[2]) if l.startswith("scale"))
truth = {}
for line in open(f"{out}/gt.txt"):
    f = line.split()
    if f and not line.startswith("#"):
        w, x, y, z, *t = map(float, f[1:8])
        r = [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
             [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
             [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]
        truth[f[0]] = [-sum(r[j][i] * t[j] for j in range(3)) for i in range(3)]
def errors(path):
    found = {}
    for line in open(path):
        r = json.loads(line)
        if r.get("success"):
            found[r["name"]] = (scale * math.dist(r["pose"]["center"], truth[r["name"]]),
                                (r.get("tracking") or {}).get("mode"))
    return found
alone, sequence = errors(f"{out}/alone.jsonl"), errors(f"{out}/sequence.jsonl")
tracked = [n for n, (_, mode) in sequence.items() if mode == "tracked" and n in alone]
if tracked:
    mine = statistics.median(sequence[n][0] for n in tracked)
    theirs = statistics.median(alone[n][0] for n in tracked)
    print(f"tracked frames: median position error {mine:.3g} m, the same {len(tracked)} frames "
          f"localized alone {theirs:.3g} m ({mine / theirs:.2f}x)")
if sys.argv[3] == "photos" and tracked:
    records = {}
    for run in ("alone", "sequence"):
        records[run] = {r["name"]: r for r in map(json.loads, open(f"{out}/{run}.jsonl"))}
    mine = statistics.median(records["sequence"][n]["tracking"]["time_ms"] for n in tracked)
    theirs = statistics.median(records["alone"][n]["times_ms"]["total"] -
                               records["alone"][n]["times_ms"]["extraction"] for n in tracked)
    features = statistics.median(r["matches"]["features"] for r in records["sequence"].values())
    print(f"tracked frame after features {mine:.2f} ms, the same frames alone {theirs:.2f} ms "
          f"({mine / theirs:.2f}); median {features:.0f} features")
    if sys.argv[4]:
        extraction = statistics.median(r["times_ms"]["extraction"]
                                       for r in records["sequence"].values())
        print(f"whole frame, decoding included: {float(sys.argv[4]) / len(records['sequence']):.0f} ms "
              f"(the run's wall time over its frames, one thread); extraction {extraction:.0f} ms")
PY
  [ -n "${PHOTO_FLAGS+set}${VIDEO_FLAGS+set}" ] || "$bin/cwloc-sequence-bench" "${frames[@]}" --rounds "$rounds"
done
