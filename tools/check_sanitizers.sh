#!/usr/bin/env bash
# The sanitizer jobs of CI (docs/reliability.md), each in its own build folder:
#   tools/check_sanitizers.sh asan   clang with ASan + UBSan (and libFuzzer's coverage) in
#                                    build-asan: builds the tests, the tools they run and the
#                                    fuzzers, runs the whole test suite but the developer tools'
#                                    own tests (CWLOC_BUILD_TOOL_TESTS)
#   tools/check_sanitizers.sh fuzz   each libFuzzer target of build-asan for FUZZ_SECONDS
#                                    (default 20), two at a time, from fuzz/corpus
#   tools/check_sanitizers.sh tsan   ThreadSanitizer in build-tsan (the device configuration,
#                                    and cwloc-serve): a batch of queries on one index with 4
#                                    threads through cwloc-localize, the library's
#                                    concurrent-use tests, SIFT on several threads inside one
#                                    photo, cwloc-serve's HTTP layer and work queue, and the
#                                    serve tests of concurrency against a ThreadSanitizer
#                                    cwloc-serve (after the native build in build/); and what
#                                    the device build links (ldd, on x86-64 only here)
set -euo pipefail
cd "$(dirname "$0")/.."
mode="${1:-}"
jobs="$(nproc)"
clang=(-DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=Release)
source tools/device_options.sh

case "$mode" in
  asan)
    cmake -S . -B build-asan -G Ninja "${clang[@]}" -DCWLOC_SANITIZE=address,undefined \
      -DCWLOC_WITH_PYTHON=OFF -DCWLOC_BUILD_FUZZERS=ON -DCWLOC_BUILD_BENCHMARKS=OFF \
      -DCWLOC_BUILD_TOOL_TESTS=OFF >/dev/null
    # The tests, the tools they run and the fuzzers: not cwloc-eval, whose tests are left out.
    cmake --build build-asan -j "$jobs" --target cwloc_test_suite cwloc_fuzzers \
      >build-asan/build.log 2>&1 || { tail -50 build-asan/build.log; exit 1; }
    # Left out: tests of accuracy on real data whose code paths other tests run sanitized (the
    # sanitizers look for memory and undefined behaviour, not for a better pose or recall). Each
    # names the test that runs its path.
    asan_skipped='^HerzJesuTest\.ExhaustivePerClusterMatchingLocalizesFromOneCluster$'  # ExhaustiveMatchingTest
    asan_skipped+='|^HerzJesuTest\.CompactIndexLocalizesEveryQueryInUnder32BytesPerView$'  # TileTest/Compact
    asan_skipped+='|^HerzJesuTest\.GlobalRatioBaselineAlsoLocalizesThisSmallModel$'  # EveryMatcherNameRuns
    asan_skipped+='|^HerzJesuTest\.AllQueriesLocalizeWithKnownFocal$'  # LocalizesEveryQueryWithValidJsonAndPoses
    asan_skipped+='|^HerzJesuTest\.AllQueriesLocalizeWithUnknownFocalAndRecoverIt$'  # DatabaseCameraWithoutPriorIsAnUnknownFocal
    asan_skipped+='|^SharedPhotoTest\.HerzJesu(FastModeSkipsTheDoubledOctave|FocalOptionIsAPrior|FocalUnknownWithinFiveCentimetres)$'  # SceauxCastleFromTheExifFocal
    asan_skipped+='|^LocalizeCliHerzJesu\.BuiltinRefinerGivesCeresPoses$'  # RefinerAgreementTest
    asan_skipped+='|^NeighborDistances\.LargeClustersAreNearlyExactAndNeverTooSmall$'  # every index build
    asan_skipped+='|^RealCaptures/CovarianceCalibrationTest\.'  # EndToEndTest (calibrated builds)
    # Our SIFT against COLMAP's features at 1600 px (23 s sanitized): SiftCwlocTest and
    # SiftImplementationTest run the same extraction sanitized on smaller images. (A
    # parameterised test's ctest name goes on with "  # GetParam() = ...": no $ after it.)
    asan_skipped+='|^(All/)?SiftAgreementTest\.'
    asan_skipped+='|^KdForest\.RecallAtTheDefaultBudget$'  # BatchEqualsOneAtATime, ExhaustiveBudgetEqualsBruteForce
    # Behaviour of whole runs (determinism, files left by killed processes, bit-for-bit
    # agreement, option echoes), 180 of the run's 770 test seconds sanitized; the paths they take
    # run sanitized in the tests named.
    asan_skipped+='|^HerzJesuTest\.AGeorefFileFromStrechasCamerasFitsToItsAlignmentResidual$'  # GeoLocalizationTest (the georeference fit)
    asan_skipped+='|^IndexCliTest\.KilledBuildsLeaveTheOldOrTheNewIndexAndNothingElse$'  # AtomicFileTest, IndexCliTest
    asan_skipped+='|^IndexCliTest\.CompactBuildSaysHowItStoresDescriptorsInInfoAndItsSchema$'  # TileTest/Compact
    asan_skipped+='|^FullAndCompact/TileTest\.ATileOfEveryClusterHoldsTheParentsSectionsBitForBit/'  # TileTest.ATileOfListedImagesHoldsTheirClusters
    asan_skipped+='|^OptionTableTest\.EverySurfaceAcceptsTheDefaults$'  # every test at the defaults
    asan_skipped+='|^IndexBuilderTest\.OutputIsByteIdenticalForTheSameInputAndAnyThreadCount$'  # IndexBuilderSharedData
    asan_skipped+='|^LocalizerApiGeoPriorsTest\.'  # LocalizerApiGeoTest
    asan_skipped+='|^TrackerCliTest\.'  # TrackerTest, VideoCliTest (the CLI's tracker)
    asan_skipped+='|^LocalizeInterruptTest\.AnInterruptedRunKeepsEveryFinishedRecord$'  # LocalizeKillTest
    asan_skipped+='|^ServeTest\.TheViewerShowsThePoseTheApiReturned$'  # ServeTest (the page is JavaScript)
    asan_skipped+='|^ServeTest\.APhotoGetsTheCliPoseBitForBit$'  # ServeTest.InfoAndMetricsSayWhatWasServed
    asan_skipped+='|^ServeLimitsTest\.AFullQueueAnswers503AtOnce$'  # WorkQueueTest, ServeLimitsTest.SigtermFinishesTheRequestsInFlight
    asan_skipped+='|^ServeTest\.GeoPoseAndCoverageOnAGeoreferencedIndex$'  # serve_request fuzzer, LocalizerApiGeoTest
    asan_skipped+='|^IndexUpdateTest\.EveryFlippedDeltaByteIsRefusedOrChangesNothing$'  # delta fuzzer (repairs checksums too)
    asan_skipped+='|^LocalizerApiToolsTest\.AppliesAnIndexDeltaAsTheUpdateWroteIt$'  # IndexUpdateTest (the same apply), delta fuzzer
    asan_skipped+='|^IndexUpdateSharedData\.ACompactHerzJesuGrownByThreeImagesKeepsPvnnExact$'  # IndexUpdateTest.ACompact* (the same paths on the fixture)
    asan_skipped+='|^FullAndCompact/TileTest\.ATileLocalizesItsQueriesAsTheWholeIndexWithTheSamePrior/'  # TileTest.ATileOfListedImagesHoldsTheirClusters, HerzJesuTest (localization)
    asan_skipped+='|^LocalizerApiGeoToolsTest\.GeoPosesWithoutPriorsAreCwlocLocalizes$'  # LocalizerApiGeoTest
    asan_skipped+='|^ServeTest\.FeaturesAsTextOrBinaryGetTheCliPoseBitForBit$'  # serve_request fuzzer, ServeTest.InfoAndMetricsSayWhatWasServed
    asan_skipped+='|^EstimateRigPose\.TheCovarianceCoversTheTruth$'  # EstimateRigPose.* (each computes the covariance; this one checks its coverage over many poses)
    # Whole runs whose paths the named tests take sanitized, 126 of the run's 770 test seconds.
    asan_skipped+='|^EndToEndTest\.EveryQueryOfTheDemoCityIsLocalizedNearItsGroundTruth$'  # LocalizeCliHerzJesu.LocalizesEveryQueryWithValidJsonAndPoses, GoldenIndexTest
    asan_skipped+='|^ServeTest\.ASessionTracksFramesAsTheCliSequenceDoes$'  # TrackerTest, ServeTest.InfoAndMetricsSayWhatWasServed, serve_request fuzzer
    asan_skipped+='|^DatabaseTest\.ReadsRealColmapDatabase$'  # DatabaseTest.*, colmap_database fuzzer, IndexBuilderSharedData
    asan_skipped+='|^OptionTableTest\.EverySurfaceRefusesAValueOutOfRangeWithTheSameMessage$'  # OptionTable.MessagesNameTheFlagAndTheRange, OptionTableTest.TheCppApiChecksItsFieldsWhenTheQueryRuns
    asan_skipped+='|^IndexUpdateTest\.KilledUpdatesAndAppliesLeaveTheParentAndNoPartialOutput$'  # AtomicFileTest, IndexUpdateTest
    asan_skipped+='|^LocalizerApiGeoToolsTest\.APositionPriorFarFromTheModelFailsSayingSo$'  # LocalizerApiGeoTest (the same in process)
    asan_skipped+='|^LocalizeCliTest\.BackMatchingModeAndBudgetAreReported$'  # LocalizeCliTest.EveryMatcherNameRunsAndIsReported, HerzJesuTest.ALatencyBudgetCutsTheStagesItEnds
    asan_skipped+='|^HerzJesuTest\.(DatabaseCameraIsTheExtractorsGuessAndIsEstimated|KeptCorrespondencesAreWhatThePoseWasFitTo)$'  # LocalizeCliHerzJesu.*
    asan_skipped+='|^VideoCliTest\.EveryNthFrameWithAnUnknownFocalLength$'  # VideoCliTest.AVideosFramesAreTrackedWithTheirTimes
    # A test that spawns our tools runs them sanitized too; any report fails the test.
    if ! ASAN_OPTIONS=abort_on_error=1:detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
      ctest --test-dir build-asan --output-on-failure -j "$jobs" -E "$asan_skipped" \
      >build-asan/ctest.log 2>&1; then
      cat build-asan/ctest.log
      exit 1
    fi
    grep 'tests passed' build-asan/ctest.log | sed 's/^/ASan + UBSan: /'
    # The tests that skipped: in CI, one tests/allowed_skips.txt does not allow for asan fails.
    tools/check_skips.py --build asan build-asan
    ;;
  fuzz)
    [ -x build-asan/bin/cwloc-fuzz-index ] || { echo "run tools/check_sanitizers.sh asan first" >&2; exit 2; }
    fuzz/run.sh build-asan --seconds "${FUZZ_SECONDS:-20}" --jobs "$jobs"
    ;;
  tsan)
    # The server too (never on a device; it links nothing the device check looks at).
    cmake -S . -B build-tsan -G Ninja "${clang[@]}" -DCWLOC_SANITIZE=thread "${device_options[@]}" \
      -DCWLOC_WITH_SERVE=ON -DCWLOC_BUILD_BENCHMARKS=OFF >/dev/null
    cmake --build build-tsan -j "$jobs" --target cwloc_localize_exe api_tests sift_tests base_tests \
      cwloc_serve_exe serve_unit_tests >build-tsan/build.log 2>&1 ||
      { tail -50 build-tsan/build.log; exit 1; }
    export TSAN_OPTIONS="halt_on_error=1 second_deadlock_stack=1"
    # The golden index's queries, each 8 times, with their cameras from the ground truth.
    golden=tests/data/golden/index-1.1-queries
    list=build-tsan/tsan-queries.txt
    for round in 1 2 3 4 5 6 7 8; do
      awk -v dir="$PWD/$golden" '!/^#/ && NF > 9 {
        line = dir "/" $1 ".txt"; for (i = 9; i <= NF; ++i) line = line " " $i; print line }' \
        "$golden/queries_gt.txt"
    done >"$list"
    build-tsan/bin/cwloc-localize --index tests/data/golden/index-1.1.cwl --query-list "$list" \
      --threads 4 -q -o build-tsan/tsan-results.jsonl
    localized=$(grep -c '"success":true' build-tsan/tsan-results.jsonl || true)
    echo "ThreadSanitizer: $(wc -l <"$list") queries on 4 threads, $localized localized, no report"
    build-tsan/tests/api_tests >build-tsan/api_tests.log 2>&1 || { cat build-tsan/api_tests.log; exit 1; }
    grep -E '^\[  PASSED  \]' build-tsan/api_tests.log | sed 's/^/ThreadSanitizer: api_tests /'
    for tests in "sift_tests:*Threads*" "base_tests:WorkerPool*"; do
      binary="${tests%%:*}"
      build-tsan/tests/"$binary" --gtest_filter="${tests#*:}" >build-tsan/"$binary".log 2>&1 ||
        { cat build-tsan/"$binary".log; exit 1; }
      grep -E '^\[  PASSED  \]' build-tsan/"$binary".log | sed "s/^/ThreadSanitizer: $binary /"
    done
    build-tsan/tests/serve_unit_tests >build-tsan/serve_unit_tests.log 2>&1 ||
      { cat build-tsan/serve_unit_tests.log; exit 1; }
    grep -E '^\[  PASSED  \]' build-tsan/serve_unit_tests.log | sed 's/^/ThreadSanitizer: serve_unit_tests /'
    # The native build's serve tests of concurrency against this cwloc-serve: its reports go to
    # files (a race ends the server, and its test fails).
    if [ -x build/tests/serve_tests ]; then
      mixed=build-tsan/serve-bin
      rm -rf "$mixed" build-tsan/serve-tsan.*
      mkdir -p "$mixed"
      for tool in build/bin/*; do ln -sf "$PWD/$tool" "$mixed/"; done
      ln -sf "$PWD/build-tsan/bin/cwloc-serve" "$mixed/cwloc-serve"
      # Sessions, a reload under two clients' load, SIGTERM with requests in flight (45 s;
      # serve_unit_tests above has the full queue's 503 and the HTTP layer's limits).
      filter='ServeTest.ASessionTracks*:ServeLimitsTest.AReloadUnderLoadFailsNoRequest'
      filter+=':ServeLimitsTest.Sigterm*'
      TSAN_OPTIONS="$TSAN_OPTIONS log_path=$PWD/build-tsan/serve-tsan" CWLOC_BIN_DIR="$PWD/$mixed" \
        build/tests/serve_tests --gtest_filter="$filter" >build-tsan/serve_tests.log 2>&1 ||
        { cat build-tsan/serve_tests.log build-tsan/serve-tsan.* 2>/dev/null; exit 1; }
      if ls build-tsan/serve-tsan.* >/dev/null 2>&1; then cat build-tsan/serve-tsan.*; exit 1; fi
      grep -E '^\[  PASSED  \]' build-tsan/serve_tests.log |
        sed 's/^/ThreadSanitizer: cwloc-serve under serve_tests /'
    fi
    # The device configuration links nothing beyond the C/C++ runtime and small C libraries
    # (clang links the sanitizer's runtime statically, so ldd shows what a device build needs).
    forbidden='sqlite|libvl\.|ceres|glog|gflags|lapack|blas|atlas|gfortran|cholmod|spqr|metis|gomp'
    forbidden+='|libav|libsw'  # FFmpeg
    for binary in build-tsan/bin/cwloc-localize build-tsan/lib/libcwloc.so; do
      if ldd "$binary" | grep -E "$forbidden"; then
        echo "device build: $binary links one of: $forbidden" >&2
        exit 1
      fi
    done
    echo "device build of cwloc-localize and libcwloc.so: OK (C/C++ runtime, libjpeg, libpng, zlib, libexif, GeographicLib)"
    ;;
  *)
    echo "usage: tools/check_sanitizers.sh asan|fuzz|tsan" >&2
    exit 2
    ;;
esac
