# Cross build for 64-bit ARM Linux on a Debian 12 x86-64 host (docs/devices.md):
#   tools/install-cross-deps.sh
#   cmake -S . -B build-arm64 -G Ninja \
#     -DCMAKE_TOOLCHAIN_FILE=cmake/toolchains/aarch64-linux-gnu.cmake ...
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(CMAKE_C_COMPILER aarch64-linux-gnu-gcc)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)

# Debian multiarch keeps both architectures under one root: arm64 libraries and their CMake
# configs in /usr/lib/aarch64-linux-gnu (which CMAKE_LIBRARY_ARCHITECTURE makes find_library
# and find_package search instead of the host's x86_64 directory), headers in /usr/include,
# arch-independent configs (Eigen3, nlohmann_json, CLI11) in /usr/share. So the root is / and
# only programs (pkg-config, qemu) are the host's.
set(CMAKE_LIBRARY_ARCHITECTURE aarch64-linux-gnu)
set(CMAKE_FIND_ROOT_PATH /)
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
# Never the host's libraries, even through a hint or a config's absolute path.
set(CMAKE_IGNORE_PATH /usr/lib/x86_64-linux-gnu /lib/x86_64-linux-gnu)

# pkg-config reads only the arm64 .pc files (and the arch-independent ones).
set(ENV{PKG_CONFIG_LIBDIR} /usr/lib/aarch64-linux-gnu/pkgconfig:/usr/share/pkgconfig)
set(ENV{PKG_CONFIG_PATH} "")

# ctest and gtest_discover_tests run the test binaries through this. qemu's default CPU (max)
# has every extension; QEMU_CPU=cortex-a53 in the environment emulates a plain ARMv8.0 core.
find_program(CWLOC_QEMU_AARCH64 qemu-aarch64 REQUIRED)
set(CMAKE_CROSSCOMPILING_EMULATOR ${CWLOC_QEMU_AARCH64})
