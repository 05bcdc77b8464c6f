#!/usr/bin/env bash
# The device build's footprint on x86-64 and aarch64: binary sizes (as built and stripped), the
# shared libraries each needs beyond the C/C++ runtime with their stripped sizes, start-up to the
# first result and peak memory for one query. aarch64 runs under qemu-user here, so its time and
# memory are the emulator's (a device's would be lower); its sizes and libraries are exact.
#
# Usage: bench/device_report.sh NATIVE_BUILD X86_DEVICE_BUILD ARM64_DEVICE_BUILD
#   NATIVE_BUILD: a full build (cwloc-index) to index ../shared/data/herz_jesu_p25.
# Prints a Markdown table (docs/benchmarks.md, "Devices").
set -euo pipefail
native=$(realpath "$1")
x86=$(realpath "$2")
arm=$(realpath "$3")
cd "$(dirname "$0")/.."
data=$(realpath ../shared/data/herz_jesu_p25)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

"$native/bin/cwloc-index" build --model "$data/mapping_model/bin" --database "$data/database.db" \
  -o "$work/herz_jesu.cwl" >/dev/null 2>&1
python3 tests/data/export_query_features.py "$data/database.db" "$work" 0012.jpg
camera=$(awk '$1 == "0012.jpg" { $1 = ""; print substr($0, 2) }' "$data/queries_with_intrinsics.txt")

runtime_re='^(libc|libm|libstdc\+\+|libgcc_s|ld-linux-x86-64|ld-linux-aarch64|libpthread|libdl|librt)\.'

# The libraries a binary needs, transitively, resolved in the architecture's multiarch folder.
needed() {
  local triplet=$1 file=$2
  local queue=("$file") seen=()
  while [ ${#queue[@]} -gt 0 ]; do
    local f=${queue[0]}
    queue=("${queue[@]:1}")
    for lib in $(readelf -d "$f" | awk '/NEEDED/ { gsub(/[\[\]]/, "", $5); print $5 }'); do
      [[ " ${seen[*]} " == *" $lib "* ]] && continue
      seen+=("$lib")
      local path
      path=$(ls /usr/lib/"$triplet"/"$lib" /lib/"$triplet"/"$lib" 2>/dev/null | head -1)
      [ -n "$path" ] && queue+=("$(realpath "$path")")
    done
  done
  printf '%s\n' "${seen[@]}" | sort
}

stripped_size() {  # bytes of a stripped copy
  local strip=$1 file=$2
  "$strip" -o "$work/stripped" "$file"
  stat -c %s "$work/stripped"
}

kb() { echo $(( ($1 + 512) / 1024 )); }

report() {
  local arch=$1 build=$2 triplet=$3 strip=$4 runner=$5
  local exe="$build/bin/cwloc-localize" lib="$build/lib/libcwloc.so"
  local exe_size lib_size extra_total=0 extras=()
  exe_size=$(stripped_size "$strip" "$exe")
  lib_size=$([ -f "$lib" ] && stripped_size "$strip" "$(realpath "$lib")" || echo 0)
  for name in $(needed "$triplet" "$exe"); do
    [[ "$name" =~ $runtime_re ]] && continue
    local path size
    path=$(realpath "$(ls /usr/lib/"$triplet"/"$name" /lib/"$triplet"/"$name" | head -1)")
    size=$(stripped_size "$strip" "$path")
    extra_total=$((extra_total + size))
    extras+=("$name $(kb "$size") kB")
  done
  local runtime
  runtime=$(needed "$triplet" "$exe" | grep -E "$runtime_re" | tr '\n' ' ')
  # Start-up to first result: open the index and localize one query, whole command.
  local features=(--index "$work/herz_jesu.cwl" --features "$work/0012.jpg.txt" --camera "$camera" -q)
  local photo=(--index "$work/herz_jesu.cwl" --image "$data/query_images/0012.jpg" --max-image-size 1600 --max-features 6000 -q)
  local t_features t_photo m_features m_photo
  t_features=$(median_ms $runner "$exe" "${features[@]}")
  t_photo=$(median_ms $runner "$exe" "${photo[@]}")
  m_features=$(peak_mb $runner "$exe" "${features[@]}")
  m_photo=$(peak_mb $runner "$exe" "${photo[@]}")
  local joined
  joined=$(printf '%s, ' "${extras[@]}")
  echo "| $arch | $(kb "$(stat -c %s "$exe")") kB / $(kb "$exe_size") kB | $(kb "$lib_size") kB | ${joined%, } | $(kb $((exe_size + extra_total))) kB | $runtime| $t_features / $t_photo | $m_features / $m_photo |"
}

median_ms() {  # median wall time of 5 runs, milliseconds
  local times=()
  for _ in 1 2 3 4 5; do
    local start end
    start=$(date +%s%N)
    "$@" >/dev/null
    end=$(date +%s%N)
    times+=($(( (end - start) / 1000000 )))
  done
  printf '%s\n' "${times[@]}" | sort -n | sed -n 3p
}

peak_mb() {  # peak resident memory of one run, MB
  /usr/bin/time -f %M "$@" 2>&1 >/dev/null | tail -1 | awk '{ printf "%.0f", $1 / 1024 }'
}

echo "| arch | cwloc-localize (built / stripped) | libcwloc.so stripped | libraries beyond the C/C++ runtime, stripped | binary + those libraries | C/C++ runtime | first result, ms: features / photo | peak memory, MB: features / photo |"
echo "|---|---|---|---|---|---|---|---|"
report x86-64 "$x86" x86_64-linux-gnu strip ""
report "aarch64 (qemu-user)" "$arm" aarch64-linux-gnu aarch64-linux-gnu-strip qemu-aarch64
