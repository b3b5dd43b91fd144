# SPDX-License-Identifier: Apache-2.0
# Cross-compiling for the sprayer's board (Raspberry Pi 4/5 class, aarch64) with Debian 12's
# cross compiler (g++-aarch64-linux-gnu) against Debian 12's arm64 libraries unpacked in a
# sysroot by cmake/toolchains/arm64-sysroot.sh (`./dev deps` makes both). Tests and build-time
# tools run under qemu-aarch64-static, called explicitly: binfmt_misc is not mounted on the CI
# machines, so an aarch64 ELF cannot be exec'd directly.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(CMAKE_C_COMPILER aarch64-linux-gnu-gcc)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)

# The sysroot: from the environment on first configure, then kept in the cache (try_compile
# projects read this file again and get it through CMAKE_TRY_COMPILE_PLATFORM_VARIABLES).
if(NOT WEEDSPRAY_ARM64_SYSROOT)
  if(DEFINED ENV{WEEDSPRAY_ARM64_SYSROOT})
    set(WEEDSPRAY_ARM64_SYSROOT "$ENV{WEEDSPRAY_ARM64_SYSROOT}")
  else()
    set(WEEDSPRAY_ARM64_SYSROOT /opt/weedspray-sysroot-arm64)
  endif()
endif()
set(WEEDSPRAY_ARM64_SYSROOT "${WEEDSPRAY_ARM64_SYSROOT}" CACHE PATH "arm64 sysroot (arm64-sysroot.sh)")
list(APPEND CMAKE_TRY_COMPILE_PLATFORM_VARIABLES WEEDSPRAY_ARM64_SYSROOT)
if(NOT EXISTS "${WEEDSPRAY_ARM64_SYSROOT}/usr/lib/aarch64-linux-gnu")
  message(FATAL_ERROR "no arm64 sysroot at ${WEEDSPRAY_ARM64_SYSROOT}: run ./dev deps")
endif()

set(CMAKE_SYSROOT "${WEEDSPRAY_ARM64_SYSROOT}")
set(CMAKE_LIBRARY_ARCHITECTURE aarch64-linux-gnu)
# Headers, libraries and CMake packages come from the sysroot only; programs from the host.
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)

# pkg-config reads the sysroot's arm64 .pc files and prefixes their paths with it.
set(ENV{PKG_CONFIG_SYSROOT_DIR} "${WEEDSPRAY_ARM64_SYSROOT}")
set(ENV{PKG_CONFIG_LIBDIR}
    "${WEEDSPRAY_ARM64_SYSROOT}/usr/lib/aarch64-linux-gnu/pkgconfig:${WEEDSPRAY_ARM64_SYSROOT}/usr/share/pkgconfig")
set(ENV{PKG_CONFIG_PATH} "")

# add_test() commands, gtest_discover_tests() and custom commands that run a built target
# go through this. -L makes qemu look up the ELF interpreter and libraries in the sysroot.
find_program(WEEDSPRAY_QEMU_AARCH64 qemu-aarch64-static REQUIRED)
set(CMAKE_CROSSCOMPILING_EMULATOR "${WEEDSPRAY_QEMU_AARCH64};-L;${WEEDSPRAY_ARM64_SYSROOT}")
