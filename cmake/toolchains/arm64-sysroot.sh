#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Makes the arm64 sysroot the aarch64 build links against and qemu-aarch64 runs from:
# Debian 12's arm64 packages of the project's libraries, unpacked (not installed) with
# mmdebstrap --variant=extract. Used by `./dev deps`; idempotent (a stamp holds the list).
#
# Why not `dpkg --add-architecture arm64` + `apt-get install lib...-dev:arm64`: OpenCV's
# imgcodecs/videoio pull libgdal32, libarmadillo11, libgdcm, libhdf4-0-alt, libogdi4.1, ...
# which are not Multi-Arch: same, so apt removes the amd64 OpenCV (and python3-opencv,
# python3-torch) to install them. And OpenCV's CMake package (OpenCVConfig.cmake) ships only
# in the libopencv-dev metapackage, whose module list fails find_package() unless every
# module's library is present, so the sysroot takes the metapackage, not single modules.
#   cmake/toolchains/arm64-sysroot.sh [DIR]     (default /opt/weedspray-sysroot-arm64)
set -euo pipefail
root="${1:-${WEEDSPRAY_ARM64_SYSROOT:-/opt/weedspray-sysroot-arm64}}"
packages=(
  libopencv-dev libgpiod-dev libmodbus-dev libv4l-dev libturbojpeg0-dev libpng-dev libspdlog-dev libsystemd-dev libgps-dev
  libtomlplusplus-dev libcli11-dev libgtest-dev libgmock-dev libbenchmark-dev nlohmann-json3-dev
  libmosquitto-dev libcpp-httplib-dev
)
case "$root" in
  /*/*) ;;
  *) echo "arm64-sysroot: refusing '$root': give an absolute directory below / (it is replaced whole)" >&2; exit 2 ;;
esac
stamp="$root/.weedspray-packages"
want="bookworm ${packages[*]}"
if [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$want" ]; then
  exit 0
fi
rm -rf "$root"
echo "arm64-sysroot: unpacking Debian 12 arm64 packages into $root"
include=$(
  IFS=,
  echo "${packages[*]}"
)
mmdebstrap --quiet --variant=extract --architectures=arm64 --format=directory \
  --skip=cleanup/apt/cache --include="$include" bookworm "$root" \
  "deb http://deb.debian.org/debian bookworm main" \
  "deb http://deb.debian.org/debian bookworm-updates main" \
  "deb http://deb.debian.org/debian-security bookworm-security main"

# Absolute symlinks (libz.so -> /lib/aarch64-linux-gnu/libz.so.1.2.13) would point into the
# host: make them relative to the sysroot so the linker and qemu -L follow them inside it.
find "$root/usr" "$root/lib" -type l -lname '/*' -print0 | while IFS= read -r -d '' link; do
  target=$(readlink "$link")
  ln -sfn "$(realpath -m --relative-to="$(dirname "$link")" "$root$target")" "$link"
done
# The maintainer scripts did not run, so update-alternatives did not make the multiarch
# links to BLAS/LAPACK (opencv_core needs libblas.so.3 and liblapack.so.3).
lib="$root/usr/lib/aarch64-linux-gnu"
for alt in blas/libblas.so.3 lapack/liblapack.so.3; do
  [ -e "$lib/$(basename "$alt")" ] || ln -s "$alt" "$lib/$(basename "$alt")"
done
# The packages' shlibs and symbols files, for dpkg-shlibdeps when CPack makes the arm64 .deb:
# nothing is in a dpkg database here, so dpkg-shlibdeps finds no package owning a sysroot
# library and falls back to the DEBIAN/ directory of the tree the library lies in (as for a
# package being built): this one.
mkdir -p "$root/DEBIAN"
: >"$root/DEBIAN/shlibs"
: >"$root/DEBIAN/symbols"
control=$(mktemp -d)
for deb in "$root"/var/cache/apt/archives/*.deb; do
  rm -rf "$control" && dpkg-deb --control "$deb" "$control"
  for kind in shlibs symbols; do
    [ ! -f "$control/$kind" ] || cat "$control/$kind" >>"$root/DEBIAN/$kind"
  done
done
rm -rf "$control" "$root"/var/cache/apt/archives/*.deb
echo "$want" >"$stamp"
