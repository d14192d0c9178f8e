# Cross-compiling ClogScope for Debian 12 arm64 (aarch64) on an amd64 Debian 12 host, against an
# arm64 sysroot of Debian's own -dev packages (scripts/arm64-check.sh makes it with mmdebstrap; see
# docs/arm64.md). The compilers come from crossbuild-essential-arm64, the tests run under qemu-user.
#
#   cmake -S . -B build-arm64 -DCMAKE_TOOLCHAIN_FILE=cmake/toolchain-arm64.cmake \
#         -DCLOGSCOPE_ARM64_SYSROOT=/path/to/sysroot -DCLOGSCOPE_PYTHON=OFF
#
# The sysroot defaults to ../arm64-sysroot beside the source tree (or $ARM64_SYSROOT).
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(CMAKE_LIBRARY_ARCHITECTURE aarch64-linux-gnu)

if(NOT CLOGSCOPE_ARM64_SYSROOT)
  if(DEFINED ENV{ARM64_SYSROOT})
    set(CLOGSCOPE_ARM64_SYSROOT "$ENV{ARM64_SYSROOT}")
  else()
    get_filename_component(CLOGSCOPE_ARM64_SYSROOT "${CMAKE_CURRENT_LIST_DIR}/../../arm64-sysroot"
                           ABSOLUTE)
  endif()
endif()
if(NOT EXISTS "${CLOGSCOPE_ARM64_SYSROOT}/usr/lib/aarch64-linux-gnu")
  message(FATAL_ERROR "no arm64 sysroot at ${CLOGSCOPE_ARM64_SYSROOT}: run scripts/arm64-check.sh")
endif()
# Try-compile projects configure with this file again: hand them the sysroot.
list(APPEND CMAKE_TRY_COMPILE_PLATFORM_VARIABLES CLOGSCOPE_ARM64_SYSROOT)

set(CMAKE_C_COMPILER aarch64-linux-gnu-gcc)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)
set(CMAKE_SYSROOT "${CLOGSCOPE_ARM64_SYSROOT}")

# Headers, libraries and CMake packages from the sysroot only; programs (pkg-config, protoc...) from
# the host.
set(CMAKE_FIND_ROOT_PATH "${CLOGSCOPE_ARM64_SYSROOT}")
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)

# pkg-config (libav*, libmicrohttpd) reads the target's .pc files and prefixes their paths with the
# sysroot.
set(ENV{PKG_CONFIG_SYSROOT_DIR} "${CLOGSCOPE_ARM64_SYSROOT}")
set(ENV{PKG_CONFIG_LIBDIR}
    "${CLOGSCOPE_ARM64_SYSROOT}/usr/lib/aarch64-linux-gnu/pkgconfig:${CLOGSCOPE_ARM64_SYSROOT}/usr/share/pkgconfig")
set(ENV{PKG_CONFIG_PATH} "")

# Test programs (and gtest_discover_tests' listing of them) run under qemu-user, the target's
# loader and libraries taken from the sysroot. Through QEMU_LD_PREFIX rather than -L: the emulated
# program's environment is the host's, so the arm64 clogscope that a command test spawns (started
# by binfmt_misc's qemu-aarch64-static) finds the sysroot too, without anything set around ctest.
set(CMAKE_CROSSCOMPILING_EMULATOR env "QEMU_LD_PREFIX=${CLOGSCOPE_ARM64_SYSROOT}" qemu-aarch64)
