#!/usr/bin/env bash
# Compare HTTP/1.1 server libraries for cwloc-serve: cpp-httplib,
# libmicrohttpd and Boost.Beast. Builds the three minimal servers in
# bench/http_libraries/ with g++ -O2 (one compile at a time), starts each on a
# free localhost port and measures it with wrk. Every server uses 2 worker
# threads with keep-alive on.
#
# Cases:
#   healthz    GET  /healthz          -> "ok"
#   post200k   POST /echo-size        200000-byte body -> body length as text
#   post200k+1ms  POST /echo-size-work same, with a 1 ms busy loop in the handler
#
# For each case the libraries run interleaved (A B C A B C ...) ROUNDS times
# so machine noise hits all of them; the table shows the median per library.
#
# Usage: bench/http_library_bench.sh            (about 2 minutes)
# Env:   DURATION (default 5s), ROUNDS (default 2), OUT (work dir, default mktemp)
set -euo pipefail

HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
SRC=$HERE/http_libraries
DURATION=${DURATION:-5s}
ROUNDS=${ROUNDS:-2}
WRK_THREADS=2
WRK_CONNS=8
OUT=${OUT:-$(mktemp -d /tmp/http_library_bench.XXXXXX)}
mkdir -p "$OUT/bin"

LIBS=(httplib microhttpd beast)
CASES=(healthz post200k post200k+1ms)

# ---------------------------------------------------------------- cleanup
SERVER_PID=""
cleanup() {
  if [[ -n "$SERVER_PID" ]] && kill -0 "$SERVER_PID" 2>/dev/null; then
    kill "$SERVER_PID" 2>/dev/null || true
    wait "$SERVER_PID" 2>/dev/null || true
  fi
  SERVER_PID=""
}
trap cleanup EXIT
trap 'exit 130' INT TERM

# ---------------------------------------------------------------- prerequisites
as_root() { if [[ $(id -u) -eq 0 ]]; then "$@"; else sudo "$@"; fi; }

if ! dpkg-query -W -f='${Status}' libmicrohttpd-dev 2>/dev/null | grep -q 'ok installed'; then
  echo "libmicrohttpd-dev is not installed: installing it with apt-get"
  if ! as_root apt-get install -y libmicrohttpd-dev >"$OUT/apt.log" 2>&1; then
    as_root apt-get update >>"$OUT/apt.log" 2>&1
    as_root apt-get install -y libmicrohttpd-dev >>"$OUT/apt.log" 2>&1
  fi
fi
for tool in g++ wrk curl pkg-config ss; do
  command -v "$tool" >/dev/null || { echo "missing tool: $tool" >&2; exit 1; }
done
pkg-config --exists cpp-httplib || { echo "missing libcpp-httplib-dev" >&2; exit 1; }
[[ -f /usr/include/boost/beast.hpp ]] || { echo "missing libboost-dev (Beast)" >&2; exit 1; }

# ---------------------------------------------------------------- build (sequential)
CXX=(g++ -O2 -std=c++17 -Wall -Wextra -pthread)
echo "Building servers in $OUT/bin ..."
# shellcheck disable=SC2046
"${CXX[@]}" -o "$OUT/bin/httplib" "$SRC/httplib_server.cc" $(pkg-config --cflags --libs cpp-httplib)
# shellcheck disable=SC2046
"${CXX[@]}" -o "$OUT/bin/microhttpd" "$SRC/microhttpd_server.cc" $(pkg-config --cflags --libs libmicrohttpd)
"${CXX[@]}" -o "$OUT/bin/beast" "$SRC/beast_server.cc"

# ---------------------------------------------------------------- helpers
free_port() {
  # Ports below the ephemeral range (wrk's client sockets live there), not
  # used by any socket in any state. httplib binds with SO_REUSEPORT, so a port
  # somebody already listens on would silently be shared: check that too.
  local p lo
  lo=$(cut -f1 /proc/sys/net/ipv4/ip_local_port_range)
  for _ in $(seq 200); do
    p=$((20000 + RANDOM % (lo - 20000)))
    if [[ -z $(ss -Htan "( sport = :$p or dport = :$p )") ]]; then echo "$p"; return; fi
  done
  echo "no free port found" >&2; exit 1
}

body_file=$OUT/body_200k.bin
head -c 200000 /dev/zero | tr '\0' 'x' >"$body_file"
lua=$OUT/post_200k.lua
cat >"$lua" <<'EOF'
wrk.method = "POST"
wrk.body = string.rep("x", 200000)
wrk.headers["Content-Type"] = "image/jpeg"
EOF

start_server() {  # lib -> sets SERVER_PID, PORT
  local lib=$1 attempt ready=0 rc
  for attempt in 1 2 3; do
    PORT=$(free_port)
    "$OUT/bin/$lib" "$PORT" >>"$OUT/$lib.log" 2>&1 &
    SERVER_PID=$!
    for _ in $(seq 100); do
      if curl -sf -o /dev/null "http://127.0.0.1:$PORT/healthz"; then ready=1; break; fi
      if ! kill -0 "$SERVER_PID" 2>/dev/null; then
        rc=0; wait "$SERVER_PID" || rc=$?
        echo "  $lib exited with status $rc on port $PORT (attempt $attempt): $(tail -1 "$OUT/$lib.log")" >&2
        SERVER_PID=""; break
      fi
      sleep 0.05
    done
    [[ $ready == 1 ]] && break
    cleanup
  done
  [[ $ready == 1 ]] || { echo "$lib server does not start, see $OUT/$lib.log" >&2; exit 1; }
  # Sanity: every case answers correctly before it is measured.
  local got
  got=$(curl -sf "http://127.0.0.1:$PORT/healthz")
  [[ $got == ok ]] || { echo "$lib: /healthz returned '$got'" >&2; exit 1; }
  for path in echo-size echo-size-work; do
    got=$(curl -sf -H 'Content-Type: image/jpeg' --data-binary "@$body_file" "http://127.0.0.1:$PORT/$path")
    [[ $got == 200000 ]] || { echo "$lib: /$path returned '$got'" >&2; exit 1; }
  done
}

wrk_args() {  # case port -> wrk arguments
  local c=$1 port=$2 common=(-t"$WRK_THREADS" -c"$WRK_CONNS" -d"$DURATION" --latency)
  case $c in
    healthz) echo "${common[*]} http://127.0.0.1:$port/healthz" ;;
    post200k) echo "${common[*]} -s $lua http://127.0.0.1:$port/echo-size" ;;
    post200k+1ms) echo "${common[*]} -s $lua http://127.0.0.1:$port/echo-size-work" ;;
  esac
}

to_ms() {  # wrk latency like 85.00us / 1.23ms / 1.02s -> ms
  awk -v v="$1" 'BEGIN {
    n = v + 0
    if (v ~ /us$/) n /= 1000; else if (v ~ /ms$/) n += 0;
    else if (v ~ /m$/) n *= 60000; else if (v ~ /s$/) n *= 1000;
    printf "%.3f", n }'
}

# ---------------------------------------------------------------- run
RAW=$OUT/raw.tsv
printf 'library\tcase\tround\treq_per_s\tp50_ms\tp99_ms\terrors\n' >"$RAW"
echo "Load average before runs: $(cut -d' ' -f1-3 /proc/loadavg)"
for c in "${CASES[@]}"; do
  for round in $(seq "$ROUNDS"); do
    for lib in "${LIBS[@]}"; do
      start_server "$lib"
      log=$OUT/wrk_${lib}_${c}_${round}.txt
      # shellcheck disable=SC2046
      wrk $(wrk_args "$c" "$PORT") >"$log" 2>&1
      cleanup
      rps=$(awk '/^Requests\/sec:/ {print $2}' "$log")
      p50=$(to_ms "$(awk '$1 == "50%" {print $2}' "$log")")
      p99=$(to_ms "$(awk '$1 == "99%" {print $2}' "$log")")
      errs=$(awk '/Socket errors:/ {gsub(",", ""); s += $4 + $6 + $8 + $10}
                  /Non-2xx or 3xx/ {s += $NF} END {print s + 0}' "$log")
      printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$lib" "$c" "$round" "$rps" "$p50" "$p99" "$errs" >>"$RAW"
      printf '  %-10s %-13s round %s: %10s req/s  p50 %8s ms  p99 %8s ms  errors %s\n' \
        "$lib" "$c" "$round" "$rps" "$p50" "$p99" "$errs"
    done
  done
done

# ---------------------------------------------------------------- report
echo
echo "CPU: $(awk -F': ' '/^model name/ {print $2; exit}' /proc/cpuinfo), $(nproc) cores;" \
  "load average after runs: $(cut -d' ' -f1-3 /proc/loadavg)"
echo "wrk: $(wrk -v 2>&1 | head -1 | cut -d' ' -f1-2); g++ $(g++ -dumpfullversion)"
echo "Versions: cpp-httplib $(dpkg-query -W -f='${Version}' libcpp-httplib-dev)," \
  "libmicrohttpd $(dpkg-query -W -f='${Version}' libmicrohttpd-dev)," \
  "boost $(dpkg-query -W -f='${Version}' libboost-dev)"
echo "wrk command (PORT = free port, one run per library, case and round):"
for c in "${CASES[@]}"; do echo "  wrk $(wrk_args "$c" PORT)"; done
echo "  $lua sets wrk.method=\"POST\", wrk.body=string.rep(\"x\", 200000), Content-Type image/jpeg"
echo
echo "Medians over $ROUNDS interleaved rounds of $DURATION (raw runs: $RAW):"
awk -F'\t' -v libs="${LIBS[*]}" -v cases="${CASES[*]}" '
  function median(key, field,   n, i, j, t, a) {
    n = cnt[key]
    for (i = 1; i <= n; i++) a[i] = val[key, i, field]
    for (i = 2; i <= n; i++) for (j = i; j > 1 && a[j-1] > a[j]; j--) { t = a[j]; a[j] = a[j-1]; a[j-1] = t }
    return (n % 2) ? a[(n + 1) / 2] : (a[n / 2] + a[n / 2 + 1]) / 2
  }
  NR > 1 { key = $1 SUBSEP $2; k = ++cnt[key]; for (f = 4; f <= 7; f++) val[key, k, f] = $f }
  END {
    printf "%-10s | %-12s | %10s | %9s | %9s | %6s\n", "library", "case", "req/s", "p50 ms", "p99 ms", "errors"
    printf "-----------+--------------+------------+-----------+-----------+-------\n"
    nc = split(cases, C, " "); nl = split(libs, L, " ")
    for (i = 1; i <= nc; i++) for (j = 1; j <= nl; j++) {
      key = L[j] SUBSEP C[i]
      printf "%-10s | %-12s | %10.0f | %9.3f | %9.3f | %6d\n", L[j], C[i],
        median(key, 4), median(key, 5), median(key, 6), median(key, 7)
    }
  }' "$RAW"

echo
echo "Server size (code lines = non-blank, non-comment; binary = unstripped / stripped bytes):"
for lib in "${LIBS[@]}"; do
  src=$SRC/${lib}_server.cc
  loc=$(grep -cvE '^\s*(//.*)?$' "$src")
  strip -o "$OUT/bin/$lib.stripped" "$OUT/bin/$lib"
  shlib=$(ldd "$OUT/bin/$lib" | awk '/httplib|microhttpd/ {print $3}')
  extra=""
  [[ -n "$shlib" ]] && extra="  + $(basename "$shlib") $(stat -L -c %s "$shlib") bytes"
  printf '  %-10s %4s lines  %8s / %8s bytes%s\n' "$lib" "$loc" \
    "$(stat -c %s "$OUT/bin/$lib")" "$(stat -c %s "$OUT/bin/$lib.stripped")" "$extra"
done
