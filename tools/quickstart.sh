#!/usr/bin/env bash
# The README's two commands.
#   tools/quickstart.sh demo   install, build, run the main job on the built-in demo city
#   tools/quickstart.sh test   install, build, run every test (the viewer's browser test too),
#                              then list the tests that skipped (tools/check_skips.py: in CI,
#                              CI=true, a skip tests/allowed_skips.txt does not allow fails)
set -euo pipefail
cd "$(dirname "$0")/.."

mode="${1:-}"
case "$mode" in
  demo|test) ;;
  *) echo "usage: tools/quickstart.sh demo|test" >&2; exit 2 ;;
esac

tools/install-deps.sh
# Chromium, Node.js and puppeteer-core for the viewer's browser test (tests/serve).
if [ "$mode" = test ]; then tools/install-browser-deps.sh; fi
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
if [ "$mode" = demo ]; then
  # The four tools the demo runs and their libraries; `test` builds the rest.
  cmake --build build -j "$(nproc)" --target cwloc_synth_exe cwloc_index_exe cwloc_localize_exe \
    cwloc_eval_exe
else
  # The tests and the tools they run (cwloc_test_suite); `cmake --build build` builds the rest,
  # the benchmarks (CI checks that they compile: tools/check_benchmarks_compile.sh).
  cmake --build build -j "$(nproc)" --target cwloc_test_suite
fi

if [ "$mode" = demo ]; then
  # The main job on the built-in demo city: generate it, index it, localize its queries
  # from their own features, and score the poses against the generated ground truth.
  demo=build/demo
  build/bin/cwloc-synth --preset demo --overwrite -o "$demo/city"
  build/bin/cwloc-index build --model "$demo/city/mapping_model/bin" --database "$demo/city/database.db" \
    -o "$demo/city.cwl"
  status=0
  build/bin/cwloc-localize --index "$demo/city.cwl" --database "$demo/city/database.db" \
    --query-list "$demo/city/queries_with_intrinsics.txt" --threads "$(nproc)" \
    -o "$demo/results.jsonl" --poses "$demo/poses.txt" -q || status=$?
  [ "$status" -le 1 ] || exit "$status"  # 1 = some queries not localized: still report them
  build/bin/cwloc-eval --results "$demo/results.jsonl" --gt "$demo/city/queries_gt.txt" \
    --scale "$demo/city/scale_to_metres.txt" --label cwloc \
    --model "$demo/city/mapping_model/bin" --gt-points "$demo/city/queries_gt_points.txt"
else
  status=0
  ctest --test-dir build --output-on-failure -j "$(nproc)" || status=$?
  tools/check_skips.py build || status=1
  exit "$status"
fi
