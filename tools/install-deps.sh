#!/usr/bin/env bash
# Installs cwloc's build and test dependencies from Debian 12's packages. Idempotent:
# does nothing when every package is already installed.
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config git
  libeigen3-dev libflann-dev libceres-dev libgeographiclib-dev
  libsqlite3-dev sqlite3 nlohmann-json3-dev libcli11-dev
  libgtest-dev libgmock-dev libbenchmark-dev libvlfeat-dev libstb-dev
  # OpenGV: the generalized pose solvers' reference in tests only.
  libopengv-dev
  libjpeg62-turbo-dev libpng-dev libexif-dev
  # jemalloc: cwloc-index's allocator, on transparent huge pages (exe/jemalloc_conf.cc).
  libjemalloc-dev
  # Video files (cwloc-localize --video; never in the device build), and ffmpeg to make the
  # tests' videos.
  libavformat-dev libavcodec-dev libavutil-dev libswscale-dev ffmpeg
  # cwloc-serve (docs/serve.md): Boost.Beast (header-only) and the viewer's three.js; the
  # tests' HTTP client (cpp-httplib), nginx and openssl for the proxy test, wrk for the load
  # benchmark.
  libboost-dev libjs-three libcpp-httplib-dev nginx-light openssl wrk
  colmap hyperfine valgrind time python3 python3-jsonschema python3-matplotlib clang-format
  # universal-ctags: where each function ends, for tools/check_function_length.py.
  universal-ctags
  # The Python module (docs/python.md): pybind11 and Python's headers, numpy, its tests, pip's
  # offline build in a venv; Dask.
  pybind11-dev python3-pybind11 python3-dev python3-numpy python3-pytest python3-setuptools
  python3-wheel python3-venv python3-distributed
  # The sanitizer and fuzz builds (docs/reliability.md): clang, its sanitizer and libFuzzer
  # runtimes, and llvm-symbolizer for readable reports.
  clang libclang-rt-14-dev llvm
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

sudo=""
if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
echo "install-deps: installing ${missing[*]}"
$sudo apt-get update -qq
DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "install-deps: done"
