#!/usr/bin/env bash
# Installs what the aarch64 cross build (cmake/toolchains/aarch64-linux-gnu.cmake) and its tests
# under qemu need, from Debian 12's multiarch packages. Idempotent: does nothing when every
# package is already installed. The native packages come from tools/install-deps.sh.
set -euo pipefail

# libstdc++6:arm64 is the runtime the test binaries load under qemu (the cross compiler's own
# copy lives in /usr/aarch64-linux-gnu, where qemu's loader does not look).
# GeographicLib: only the arm64 runtime library. libgeographiclib-dev is not Multi-Arch: same,
# so its arm64 package would remove the host's (which the native build needs); the cross build
# links /usr/lib/aarch64-linux-gnu/libGeographicLib.so.23 with the host -dev's headers, which
# are the same on both (geo/CMakeLists.txt).
packages=(
  crossbuild-essential-arm64 qemu-user
  libstdc++6:arm64 libjpeg62-turbo-dev:arm64 libpng-dev:arm64 zlib1g-dev:arm64
  libexif-dev:arm64 libgtest-dev:arm64 libgmock-dev:arm64 libgeographiclib23:arm64
)

have_arch=0
dpkg --print-foreign-architectures | grep -qx arm64 && have_arch=1
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ "$have_arch" -eq 1 ] && [ ${#missing[@]} -eq 0 ]; then
  echo "install-cross-deps: arm64 architecture and all ${#packages[@]} packages present"
  exit 0
fi

sudo=""
if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
if [ "$have_arch" -eq 0 ]; then
  echo "install-cross-deps: adding the arm64 architecture"
  $sudo dpkg --add-architecture arm64
fi
echo "install-cross-deps: installing ${missing[*]}"
$sudo apt-get update -qq
DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "install-cross-deps: done"
