#!/usr/bin/env bash
# Remakes the seed corpora in fuzz/corpus/ from a generated scene and the small real files in
# the repository (tests/data) and ../shared/data. They are kept small: libFuzzer's inputs never
# grow past its largest seed, and small inputs run fast.
#   fuzz/make_corpora.sh BUILD_DIR    (a build with the tools and cwloc-fuzz-make-model-seeds)
set -euo pipefail
cd "$(dirname "$0")/.."
build="${1:?usage: fuzz/make_corpora.sh BUILD_DIR}"
bin="$build/bin"
corpus=fuzz/corpus
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

rm -rf "$corpus"
mkdir -p "$corpus"/{index,delta,colmap_model,colmap_database,feature_file,query_list,photo,georef,serve_request}

# A scene of 4 registered images and ~70 points, placed on the globe.
"$bin/cwloc-synth" --blocks 1 --queries 2 --camera-spacing 15 --features-per-image 100 \
  --geo "47.3769 8.5417 408" -o "$work/scene" >/dev/null
scene="$work/scene"
"$bin/cwloc-index" build --model "$scene/mapping_model/bin" --database "$scene/database.db" \
  --georef "$scene/georef.txt" -o "$corpus/index/georeferenced.cwl" >/dev/null
"$bin/cwloc-index" build --model "$scene/mapping_model/bin" --database "$scene/database.db" \
  --keypoints -o "$corpus/index/with-keypoints.cwl" >/dev/null

# A delta (fuzz/delta_fuzzer.cc: u32 parent size, the parent, the delta): the scene without its
# last image, updated to the whole scene.
last=$(sqlite3 "$scene/database.db" "select max(image_id) from images where name like 'map_%'")
echo "$last" >"$work/last.txt"
mkdir -p "$work/old"
colmap image_deleter --input_path "$scene/mapping_model/bin" --output_path "$work/old" \
  --image_ids_path "$work/last.txt" >/dev/null 2>&1
"$bin/cwloc-index" build --model "$work/old" --database "$scene/database.db" \
  --calibration-samples 0 -o "$work/old.cwl" >/dev/null
"$bin/cwloc-index" update --index "$work/old.cwl" --model "$scene/mapping_model/bin" \
  --database "$scene/database.db" -o "$work/new.cwl" --delta "$work/new.cwld" >/dev/null
python3 -c "import os, struct, sys; p = open(sys.argv[1], 'rb').read(); sys.stdout.buffer.write(struct.pack('<I', len(p)) + p + open(sys.argv[2], 'rb').read())" \
  "$work/old.cwl" "$work/new.cwld" >"$corpus/delta/grown-by-one-image.bin"

# A compact index's delta (1.1: NCOD): a scene with enough points (256) to learn codes from.
"$bin/cwloc-synth" --blocks 1 --queries 1 --camera-spacing 15 --features-per-image 400 \
  -o "$work/compact_scene" >/dev/null
compact_scene="$work/compact_scene"
last=$(sqlite3 "$compact_scene/database.db" "select max(image_id) from images where name like 'map_%'")
echo "$last" >"$work/compact_last.txt"
mkdir -p "$work/compact_old"
colmap image_deleter --input_path "$compact_scene/mapping_model/bin" \
  --output_path "$work/compact_old" --image_ids_path "$work/compact_last.txt" >/dev/null 2>&1
"$bin/cwloc-index" build --compact --code-bytes 8 --model "$work/compact_old" \
  --database "$compact_scene/database.db" --calibration-samples 0 -o "$work/compact_old.cwl" >/dev/null
"$bin/cwloc-index" update --index "$work/compact_old.cwl" \
  --model "$compact_scene/mapping_model/bin" --database "$compact_scene/database.db" \
  -o "$work/compact_new.cwl" --delta "$work/compact_new.cwld" >/dev/null
python3 -c "import os, struct, sys; p = open(sys.argv[1], 'rb').read(); sys.stdout.buffer.write(struct.pack('<I', len(p)) + p + open(sys.argv[2], 'rb').read())" \
  "$work/compact_old.cwl" "$work/compact_new.cwld" >"$corpus/delta/compact-grown-by-one-image.bin"

# A compact index (format 1.2: PORG, PNTF, PQCB, PCOD, PVNN) needs 256 points to learn its codes,
# more than the scene has: the golden one.
cp tests/data/golden/index-1.2.cwl "$corpus/index/compact.cwl"

"$bin/cwloc-fuzz-make-model-seeds" "$scene/mapping_model/bin" "$corpus/colmap_model"

# The database with 20 features per image, without matches, in 512-byte pages.
"$bin/cwloc-synth" --blocks 1 --queries 2 --camera-spacing 15 --features-per-image 20 \
  -o "$work/small" >/dev/null
sqlite3 "$work/small/database.db" \
  "DELETE FROM matches; DELETE FROM two_view_geometries; PRAGMA page_size=512; VACUUM;"
cp "$work/small/database.db" "$corpus/colmap_database/synth.db"

# A query's features cut to 6 (the header's count with them), and an empty file of features.
features=tests/data/golden/index-1.1-queries/query_00001.jpg.txt
{ echo "6 128"; sed -n 2,7p "$features"; } >"$corpus/feature_file/six.txt"
echo "0 128" >"$corpus/feature_file/none.txt"

cp "$scene/queries_with_intrinsics.txt" "$corpus/query_list/with-cameras.txt"
cp "$scene/query_list.txt" "$corpus/query_list/names.txt"
cp "$scene/query_priors.txt" "$corpus/query_list/priors.txt"
# A --motion file: frames' relative motion from VIO.
printf '# VIO\n0004.jpg 0.99999 0.0033 -0.0024 -0.0015 0.185 0.019 -0.060\n0007.jpg 1 0 0 0 -0.59 0.10 -0.08\n' \
  >"$corpus/query_list/motion.txt"

cp tests/data/photos/* "$corpus/photo/"
# A real iPhone photo's EXIF (focal length and GPS) in front of a small JPEG.
python3 - ../shared/data/exif_samples/berlin_iphone4s/01.jpg tests/data/photos/grey.jpg \
  "$corpus/photo/iphone-exif.jpg" <<'PY'
import sys
exif_photo, small, out = (open(p, "rb").read() if i < 2 else p for i, p in enumerate(sys.argv[1:]))
at = 2
while exif_photo[at + 1] != 0xE1:  # walk the segments to APP1
    at += 2 + int.from_bytes(exif_photo[at + 2:at + 4], "big")
app1 = exif_photo[at:at + 2 + int.from_bytes(exif_photo[at + 2:at + 4], "big")]
open(out, "wb").write(small[:2] + app1 + small[2:])
PY

cp "$scene/georef.txt" "$corpus/georef/scene.txt"
head -3 "$scene/georef.txt" | awk '{print $0, 2.5}' >"$corpus/georef/with-sigmas.txt"
# cwloc-serve's request parts (fuzz/serve_request_fuzzer.cc: a first byte picks the part).
request="$corpus/serve_request"
printf 'o{"max-features": 4000, "nb": 5, "camera": "SIMPLE_RADIAL 640 480 500 320 240 0.01", "prior_position": [47.1, 8.2, 30], "motion": "1 0 0 0 0.1 0 0 1 0.5", "use-exif-gps": true, "name": "a"}' \
  >"$request/options.txt"
printf 'g{"id":"1","sensorReadings":{"cameraReadings":[{"imageFormat":"GRAY8","size":[2,2],"imageBytes":"AAECAw==","params":{"model":"PINHOLE","modelParams":[500,500,1,1]}}],"geolocationReadings":[{"latitude":47.1,"longitude":8.2,"accuracy":20}]}}' \
  >"$request/geopose.txt"
{ printf 'f'; sed -n 1,3p "$corpus/feature_file/six.txt" | sed '1s/.*/2 128/'; } >"$request/features.txt"
python3 -c "import struct, sys; sys.stdout.buffer.write(b'fCWLF' + struct.pack('<II4f', 1, 2, 1.5, 2.5, 3.5, 4.5) + bytes(range(256)))" \
  >"$request/features-binary.bin"

du -sh "$corpus"/*
