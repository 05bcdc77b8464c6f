#!/usr/bin/env bash
# Two builds give the same outputs: index files (full and --compact) byte for byte, cwloc-localize's
# pose lines byte for byte and its JSON lines byte for byte but for times_ms, on herz_jesu_p25,
# sceaux_castle (their database queries, and herz_jesu's photos) and the demo city, whose
# cwloc-synth files must match too. For a change that should not change any answer.
# Usage: tools/check_same_outputs.sh OLD_BIN_DIR NEW_BIN_DIR OUT_DIR (bin folders with
# cwloc-index, cwloc-localize and cwloc-synth). Prints one line per comparison.
# IGNORE_KEYS (default "times_ms") are the JSON records' keys left out of the comparison; a
# change to what a record reports adds its key ("times_ms parameters").
set -euo pipefail
old=$1 new=$2 out=$3
ignore_keys=${IGNORE_KEYS:-times_ms}
mkdir -p "$out"
status=0  # 1 once anything differs
strip_times() { python3 -c '
import json,sys
for line in open(sys.argv[1]):
    r=json.loads(line)
    for key in sys.argv[2].split(): r.pop(key,None)
    print(json.dumps(r,sort_keys=False))' "$1" "$ignore_keys"; }
run() {  # NAME MODEL DB then localize args
  local name=$1 model=$2 db=$3; shift 3
  for v in old new; do
    local bin; bin=$([ $v = old ] && echo "$old" || echo "$new")
    "$bin/cwloc-index" build --model "$model" --database "$db" -o "$out/$name.$v.cwl" >/dev/null 2>&1
    "$bin/cwloc-index" build --model "$model" --database "$db" --compact -o "$out/$name.$v.compact.cwl" >/dev/null 2>&1
    for kind in "" ".compact"; do
      local st=0
      "$bin/cwloc-localize" --index "$out/$name.$v$kind.cwl" --database "$db" "$@" -q \
        -o "$out/$name$kind.$v.jsonl" --poses "$out/$name$kind.$v.poses" || st=$?
      [ $st -le 1 ] || { echo "$v $name$kind: exit $st"; exit 1; }
      strip_times "$out/$name$kind.$v.jsonl" > "$out/$name$kind.$v.notimes.jsonl"
    done
  done
  for kind in "" ".compact"; do
    cmp -s "$out/$name.old$kind.cwl" "$out/$name.new$kind.cwl" && i=identical || { i=DIFFER; status=1; }
    cmp -s "$out/$name$kind.old.poses" "$out/$name$kind.new.poses" && p=identical || { p=DIFFER; status=1; }
    cmp -s "$out/$name$kind.old.notimes.jsonl" "$out/$name$kind.new.notimes.jsonl" && j=identical || { j=DIFFER; status=1; }
    echo "$name$kind: index $i, poses $p ($(wc -l < "$out/$name$kind.new.poses") lines), JSON without $ignore_keys $j ($(wc -l < "$out/$name$kind.new.jsonl") records)"
  done
}
d="$(cd "$(dirname "$0")/../.." && pwd)/shared/data"
run herz_jesu_p25 $d/herz_jesu_p25/mapping_model/bin $d/herz_jesu_p25/database.db --query-list $d/herz_jesu_p25/queries_with_intrinsics.txt
run sceaux_castle $d/sceaux_castle/mapping_model/bin $d/sceaux_castle/database.db --query-list $d/sceaux_castle/queries_with_intrinsics.txt
for v in old new; do
  bin=$([ $v = old ] && echo "$old" || echo "$new")
  "$bin/cwloc-synth" --preset demo --overwrite -o "$out/city.$v" >/dev/null 2>&1
done
for f in mapping_model/bin/cameras.bin mapping_model/bin/images.bin mapping_model/bin/points3D.bin queries_gt.txt database.db; do
  cmp -s "$out/city.old/$f" "$out/city.new/$f" && echo "demo city $f: identical" || { echo "demo city $f: DIFFER"; status=1; }
done
run demo_city $out/city.new/mapping_model/bin $out/city.new/database.db --query-list $out/city.new/queries_with_intrinsics.txt
# Photos in: herz_jesu's query photos
for v in old new; do
  bin=$([ $v = old ] && echo "$old" || echo "$new")
  st=0
  "$bin/cwloc-localize" --index "$out/herz_jesu_p25.new.cwl" --image-list $d/herz_jesu_p25/query_list.txt \
    --image-dir $d/herz_jesu_p25/query_images --max-image-size 1600 --max-features 6000 -q \
    -o "$out/photos.$v.jsonl" --poses "$out/photos.$v.poses" || st=$?
  strip_times "$out/photos.$v.jsonl" > "$out/photos.$v.notimes.jsonl"
done
cmp -s "$out/photos.old.poses" "$out/photos.new.poses" && p=identical || { p=DIFFER; status=1; }
cmp -s "$out/photos.old.notimes.jsonl" "$out/photos.new.notimes.jsonl" && j=identical || { j=DIFFER; status=1; }
echo "herz_jesu photos: poses $p, JSON without $ignore_keys $j"
exit "$status"
