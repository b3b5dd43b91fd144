#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Builds weedspray's .deb the way a user does: a Release tree configured with
# -DCMAKE_INSTALL_PREFIX=/usr and tests off, then `cpack -G DEB`. Prints the .deb's path.
#
#   build-deb.sh --source DIR --tree DIR [--no-failsafe ON|OFF]
#
# --tree: the package tree, made when missing and rebuilt incrementally; its logs are
# TREE.configure.log, TREE.build.log and TREE.cpack.log. Its compile commands are those of the
# default preset's tree but for the two files whose defines depend on the install prefix
# (daemon/CMakeLists.txt), so with ccache most of the build is cache hits.
# --no-failsafe ON: the harness self-test's daemon (tests/vm-systemd); OFF (the default)
# switches a tree left that way back.
set -Eeuo pipefail

source_dir=""
tree=""
no_failsafe=OFF
die() {
  echo "build-deb: error: $*" >&2
  exit 2
}
note() { echo "build-deb: $*" >&2; }

while (($#)); do
  case "$1" in
    --source) source_dir="${2:?--source needs a directory}"; shift 2 ;;
    --tree) tree="${2:?--tree needs a directory}"; shift 2 ;;
    --no-failsafe) no_failsafe="${2:?--no-failsafe needs ON or OFF}"; shift 2 ;;
    -h | --help) sed -n '2,12p' "$0"; exit 0 ;;
    *) die "unknown argument '$1' (see --help)" ;;
  esac
done
[ -f "$source_dir/CMakeLists.txt" ] || die "--source '$source_dir' is not the weedspray checkout"
[ -n "$tree" ] || die "--tree is required (see --help)"
case "$no_failsafe" in ON | OFF) ;; *) die "--no-failsafe takes ON or OFF" ;; esac
for tool in cmake cpack ninja dpkg-shlibdeps; do
  command -v "$tool" >/dev/null 2>&1 || die "'$tool' not found (./dev deps installs it)"
done

started=$SECONDS
mkdir -p "$tree" || die "cannot create the package tree '$tree'"
if [ ! -f "$tree/CMakeCache.txt" ]; then
  note "configuring $tree (Release, CMAKE_INSTALL_PREFIX=/usr, BUILD_TESTING=OFF)"
  cmake -S "$source_dir" -B "$tree" -G Ninja -DCMAKE_BUILD_TYPE=Release \
    -DCMAKE_INSTALL_PREFIX=/usr -DBUILD_TESTING=OFF >"$tree.configure.log" 2>&1 || {
    cat "$tree.configure.log" >&2
    die "configuring the package tree failed"
  }
fi
if ! grep -qx "WEEDSPRAY_SELFTEST_NO_FAILSAFE:BOOL=$no_failsafe" "$tree/CMakeCache.txt"; then
  cmake -DWEEDSPRAY_SELFTEST_NO_FAILSAFE="$no_failsafe" "$tree" >>"$tree.configure.log" 2>&1 ||
    die "cannot set WEEDSPRAY_SELFTEST_NO_FAILSAFE=$no_failsafe in $tree"
fi
cmake --build "$tree" -j"$(nproc)" >"$tree.build.log" 2>&1 || {
  tail -n 50 "$tree.build.log" >&2
  die "building the package tree failed (log: $tree.build.log)"
}
rm -f "$tree"/weedspray_*.deb "$tree"/weedspray-*_*.deb
(cd "$tree" && cpack -G DEB) >"$tree.cpack.log" 2>&1 || {
  cat "$tree.cpack.log" >&2
  die "cpack -G DEB failed"
}
debs=("$tree"/weedspray_*.deb)
[ -f "${debs[0]}" ] || die "cpack made no weedspray_*.deb in $tree"
note "package $(basename "${debs[0]}") built in $((SECONDS - started)) s"
echo "${debs[0]}"
