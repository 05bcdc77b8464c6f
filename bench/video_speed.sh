#!/usr/bin/env bash
# Whole video frames at 30 frames per second: decoding, extraction and tracking, one and two
# threads (docs/benchmarks.md, "Sequences"). ../shared holds no real 30 fps clip, so the clip is
# made: one of fox_video's query photos (1080 x 1920), panned, zoomed and turned a little at 30
# frames per second for 6 seconds and encoded as a phone encodes (H.264, 16 Mbit/s), so that
# decoding costs what a phone's stream costs; the frames are tracked against fox_video's map.
#
#   bench/video_speed.sh WORKDIR
#   CWLOC_BIN=/tmp/bin bench/video_speed.sh /tmp/video
#
# Prints, per frame setting and thread count, the run's wall time over its frames (decoding,
# extraction, tracking and the index's opening, so an upper bound of a frame's time), and the
# medians of extraction and tracking from the records.
set -euo pipefail
top="$(cd "$(dirname "$0")/.." && pwd)"
bin="${CWLOC_BIN:-$top/build/bin}"
[ $# -eq 1 ] || { echo "usage: $0 WORKDIR" >&2; exit 2; }
work="$(realpath -m "$1")"
data="$top/../shared/data/fox_video"
[ -d "$data" ] || { echo "$0: $data not found" >&2; exit 2; }
for tool in ffmpeg ffprobe; do
  command -v "$tool" >/dev/null || { echo "$0: $tool not found" >&2; exit 2; }
done
for tool in cwloc-index cwloc-localize; do
  [ -x "$bin/$tool" ] || { echo "$0: $bin/$tool not found (build first, or set CWLOC_BIN)" >&2; exit 2; }
done
mkdir -p "$work"

photo=0029.jpg
clip="$work/pan30.mp4"
if [ ! -f "$clip" ]; then
  # A 1012 x 1800 window (the frame's aspect) moving over the photo, scaled to 1080 x 1920:
  # the camera's focal length is the photo's times 1920 / 1800.
  ffmpeg -loglevel error -y -loop 1 -framerate 30 -i "$data/query_images/$photo" \
    -vf "crop=1012:1800:'34+34*sin(t)':'60+60*sin(0.7*t)',scale=1080:1920,rotate=0.03*sin(2*t)" \
    -t 6 -c:v libx264 -preset fast -b:v 16M -maxrate 20M -bufsize 16M -pix_fmt yuv420p \
    -f mp4 "$clip.part"
  mv "$clip.part" "$clip"
fi
camera="$(awk -v photo="$photo" '$1 == photo {
  printf "%s 1080 1920 %.2f 540 960 %s", $2, $5 * 1920 / 1800, $8 }' "$data/queries_with_intrinsics.txt")"
[ -n "$camera" ] || { echo "$0: $photo is not in $data/queries_with_intrinsics.txt" >&2; exit 2; }
[ -f "$work/fox.cwl" ] ||
  "$bin/cwloc-index" build --model "$data/mapping_model/bin" --database "$data/database.db" \
    -o "$work/fox.cwl" >"$work/index.log"

frames="$(ffprobe -v error -count_frames -select_streams v -show_entries stream=nb_read_frames \
  -of csv=p=0 "$clip")"
now_ms() { echo $(($(date +%s%N) / 1000000)); }
start=$(now_ms)
ffmpeg -loglevel error -threads 1 -i "$clip" -f null -
decode_ms=$(($(now_ms) - start))
echo "CPU: $(lscpu | sed -n 's/^Model name: *//p' | head -1); clip: $frames frames of 1080 x 1920," \
  "$(($(stat -c %s "$clip") * 8 * 30 / frames / 1000000)) Mbit/s; ffmpeg -threads 1 decodes a frame" \
  "in $((decode_ms / frames)) ms"
echo
echo "| settings | threads | whole frame (ms) | extraction (ms) | tracker (ms) | tracked |"
echo "|---|---|---|---|---|---|"
for setting in "480 1000" "640 1500" "960 2000"; do
  read -r size features <<<"$setting"
  for threads in 1 2; do
    out="$work/pan_${size}_$threads.jsonl"
    start=$(now_ms)
    "$bin/cwloc-localize" --index "$work/fox.cwl" --video "$clip" --camera "$camera" \
      --first-octave 0 --max-image-size "$size" --max-features "$features" --threads "$threads" \
      -q -o "$out" || [ $? -eq 1 ]  # 1: some frames lost, still timed
    wall_ms=$(($(now_ms) - start))
    python3 - "$out" "$wall_ms" "$size" "$features" "$threads" <<'PY'
import json, statistics, sys
path, wall_ms, size, features, threads = sys.argv[1:]
records = [json.loads(line) for line in open(path)]
extraction = statistics.median(r["times_ms"]["extraction"] for r in records)
tracker = statistics.median(r["tracking"]["time_ms"] for r in records)
tracked = sum(r["tracking"]["mode"] == "tracked" for r in records)
print(f"| {size} px, first octave 0, {features} features | {threads} | "
      f"{float(wall_ms) / len(records):.1f} | {extraction:.1f} | {tracker:.2f} | "
      f"{tracked}/{len(records)} |")
PY
  done
done
