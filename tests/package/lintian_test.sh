#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Builds the .debs (tools/build-deb.sh: weedspray and the packages beside it, weedspray-maps,
# -fleet, -lab) and runs Debian's lintian on each: any error (E:), or lintian itself failing,
# fails the test. Warnings are printed, not failed on.
#   lintian_test.sh --source DIR --tree DIR
set -euo pipefail
source_dir=""
tree=""
while (($#)); do
  case "$1" in
    --source) source_dir="${2:?--source needs a directory}"; shift 2 ;;
    --tree) tree="${2:?--tree needs a directory}"; shift 2 ;;
    *) echo "lintian_test: unknown argument '$1'" >&2; exit 2 ;;
  esac
done
command -v lintian >/dev/null 2>&1 || {
  echo "lintian_test: 'lintian' not found: install the Debian package 'lintian' (./dev deps)" >&2
  exit 2
}
deb="$("$source_dir/tools/build-deb.sh" --source "$source_dir" --tree "$tree")"
debs=("$deb")
for other in "$(dirname "$deb")"/weedspray-*_*.deb; do [ -f "$other" ] && debs+=("$other"); done
((${#debs[@]} == 4)) || {
  echo "lintian_test: FAIL: expected weedspray and weedspray-{maps,fleet,lab}, got: ${debs[*]}" >&2
  exit 1
}
failed=0
for deb in "${debs[@]}"; do
  rc=0
  report="$(lintian --fail-on error --tag-display-limit 0 --info "$deb" 2>&1)" || rc=$?
  echo "$report"
  if ((rc != 0)) || grep -q '^E:' <<<"$report"; then
    echo "lintian_test: FAIL: lintian exit status $rc, errors on $(basename "$deb") above" >&2
    failed=1
  else
    echo "lintian_test: $(basename "$deb"): no lintian errors"
  fi
done
exit "$failed"
