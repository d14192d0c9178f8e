#!/usr/bin/env bash
# Cross-builds ClogScope for Debian 12 arm64 and runs its unit tests under qemu-user (docs/arm64.md).
# Idempotent: installs only what is missing, reuses the sysroot and build-arm64/ when present.
#
#   scripts/arm64-check.sh             # install, configure, build, test
#   JOBS=2 scripts/arm64-check.sh      # build jobs (default 1)
#   ARM64_SYSROOT=/some/dir ...        # where the arm64 sysroot lives (default: ../arm64-sysroot)
#   CTEST_ARGS="-R Csv" ...            # more ctest arguments
#
# Why a sysroot and not Debian multiarch: several -dev packages the build needs are not
# Multi-Arch: same, so their :arm64 builds replace the amd64 ones (libopencv-dev, libyaml-cpp-dev,
# libgoogle-glog-dev and libgflags-dev under libceres-dev, libgdal32/libgdcm-dev/libopenexr-dev
# and more under OpenCV's imgcodecs): installing them would remove the native build's packages. Instead mmdebstrap unpacks Debian's arm64 packages (no maintainer scripts run) into
# a directory that the cross compiler uses as --sysroot and qemu-aarch64 as its -L prefix.
set -euo pipefail
cd "$(dirname "$0")/.."
repo=$(pwd)
sysroot=${ARM64_SYSROOT:-$(cd .. && pwd)/arm64-sysroot}
build_dir=${BUILD_DIR:-build-arm64}
jobs=${JOBS:-1}

SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  if command -v sudo >/dev/null 2>&1; then SUDO="sudo"; else
    echo "arm64-check: needs root or sudo (apt-get, mmdebstrap, binfmt_misc)" >&2
    exit 1
  fi
fi
export DEBIAN_FRONTEND=noninteractive

# 1. Host tools: the cross compilers, qemu-user (and its static build, registered with
#    binfmt_misc so that a test's posix_spawn of the arm64 clogscope runs too), mmdebstrap.
host_packages=(cmake pkg-config crossbuild-essential-arm64 qemu-user qemu-user-static binfmt-support
               mmdebstrap)
missing=()
for p in "${host_packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed'; then
    missing+=("$p")
  fi
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "arm64-check: installing ${missing[*]}"
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

# 2. The arm64 sysroot: Debian 12's arm64 builds of scripts/install-deps.sh's libraries (less the
#    Python module's, which is not cross-built) with their dependencies, unpacked. Remade when this
#    list changes (the stamp holds it).
target_packages=(
  libc6-dev libstdc++-12-dev libgcc-12-dev
  libopencv-dev libceres-dev libeigen3-dev libgtest-dev libcli11-dev libspdlog-dev libfmt-dev
  nlohmann-json3-dev libyaml-cpp-dev libavformat-dev libavcodec-dev libavutil-dev libswscale-dev
  libmicrohttpd-dev libcurl4-openssl-dev libmosquitto-dev libpng-dev libjpeg-dev libv4l-dev
)
stamp="$sysroot/.clogscope-sysroot"
want="bookworm arm64 ${target_packages[*]}"
if [ ! -f "$stamp" ] || [ "$(cat "$stamp")" != "$want" ]; then
  echo "arm64-check: unpacking the arm64 sysroot into $sysroot (~1.2 GB, ~1 min)"
  $SUDO rm -rf "$sysroot.partial"
  include=$(IFS=,; echo "${target_packages[*]}")
  $SUDO mmdebstrap --quiet --variant=extract --architectures=arm64 --include="$include" bookworm \
    "$sysroot.partial" \
    "deb http://deb.debian.org/debian bookworm main" \
    "deb http://deb.debian.org/debian bookworm-updates main" \
    "deb http://deb.debian.org/debian-security bookworm-security main"
  # No maintainer script ran: make the links update-alternatives would have made. BLAS and LAPACK
  # (under Ceres) as on an amd64 host with the same packages: ATLAS, the highest priority.
  for l in libblas.so.3 libblas.so liblapack.so.3 liblapack.so; do
    $SUDO ln -sfn "atlas/$l" "$sysroot.partial/usr/lib/aarch64-linux-gnu/$l"
  done
  # Ceres's exported target names BLAS, LAPACK and ATLAS by absolute path (/usr/lib/...): point
  # them into the sysroot (CMake expands ${CMAKE_SYSROOT} when it reads the file).
  $SUDO sed -i 's|;/usr/lib/aarch64-linux-gnu/|;${CMAKE_SYSROOT}/usr/lib/aarch64-linux-gnu/|g' \
    "$sysroot.partial/usr/lib/aarch64-linux-gnu/cmake/Ceres/CeresTargets.cmake"
  echo "$want" | $SUDO tee "$sysroot.partial/.clogscope-sysroot" >/dev/null
  $SUDO rm -rf "$sysroot"
  $SUDO mv "$sysroot.partial" "$sysroot"
fi

# 3. binfmt_misc: the tests that spawn build-arm64/bin/clogscope exec an arm64 program from an
#    emulated one; the kernel hands it to qemu-aarch64-static, which finds the loader and libraries
#    through QEMU_LD_PREFIX (set by the toolchain file's CMAKE_CROSSCOMPILING_EMULATOR).
if [ ! -e /proc/sys/fs/binfmt_misc/status ]; then
  $SUDO mount -t binfmt_misc binfmt_misc /proc/sys/fs/binfmt_misc
fi
if [ ! -e /proc/sys/fs/binfmt_misc/qemu-aarch64 ]; then
  $SUDO update-binfmts --enable qemu-aarch64
fi

# 4. Configure, build (Release; no Python module: it would need an arm64 Python with NumPy and
#    pandas under the emulator).
cmake -S . -B "$build_dir" -DCMAKE_TOOLCHAIN_FILE="$repo/cmake/toolchain-arm64.cmake" \
  -DCLOGSCOPE_ARM64_SYSROOT="$sysroot" -DCMAKE_BUILD_TYPE=Release -DCLOGSCOPE_PYTHON=OFF >/dev/null
cmake --build "$build_dir" -j "$jobs"

# 5. The unit tests under qemu-aarch64 (CMAKE_CROSSCOMPILING_EMULATOR), less the slow-labelled
#    cases (statistical matrices and Greeff's whole video: minutes natively, far longer emulated).
cd "$build_dir"
# shellcheck disable=SC2086
ctest --output-on-failure -j "$jobs" -LE slow ${CTEST_ARGS:-}
