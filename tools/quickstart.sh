#!/usr/bin/env bash
# The README's two commands.
#   tools/quickstart.sh demo   install, build, run the main job on the built-in demo city
#   tools/quickstart.sh test   install, build, run every test
set -euo pipefail
cd "$(dirname "$0")/.."

mode="${1:-}"
case "$mode" in
  demo|test) ;;
  *) echo "usage: tools/quickstart.sh demo|test" >&2; exit 2 ;;
esac

tools/install-deps.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j "$(nproc)"

if [ "$mode" = demo ]; then
  build/bin/cwloc-synth --preset demo --overwrite -o build/demo/city
else
  ctest --test-dir build --output-on-failure -j "$(nproc)"
fi
