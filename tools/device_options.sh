# The device configuration's CMake options (docs/devices.md), sourced by .ci/run (the aarch64
# build) and tools/check_sanitizers.sh (the ThreadSanitizer build, whose links CI checks as the
# device build's): no SQLite or COLMAP readers, no tools, no VLFeat, no Ceres, no Python, no
# FFmpeg, no server.
# shellcheck disable=SC2034
device_options=(-DCWLOC_WITH_COLMAP_DB=OFF -DCWLOC_BUILD_TOOLS=OFF -DCWLOC_WITH_VLFEAT=OFF
  -DCWLOC_WITH_CERES=OFF -DCWLOC_WITH_PYTHON=OFF -DCWLOC_WITH_VIDEO=OFF -DCWLOC_WITH_SERVE=OFF)
