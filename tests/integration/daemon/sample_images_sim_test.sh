#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The sample field images in the repository (sim/field-images) are a field the simulated sprayer
# sees: `weedsprayd --sim --sim-images sim/field-images` sprays and opens nozzles on their
# plants, as in a clone without the shared data folder.
#   sample_images_sim_test.sh BUILD_DIR SOURCE_DIR
set -euo pipefail
build="$1" source="$2"
images="$source/sim/field-images"
fail() { echo "FAIL: $*" >&2; exit 1; }
count="$(find "$images" -maxdepth 1 -name '*.png' | wc -l)"
[ "$count" -ge 4 ] || fail "$images holds $count PNG photos, expected at least 4"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
printf '[daemon]\nautostart = true\n' >"$tmp/weedspray.toml"
"$build/daemon/weedsprayd" --sim --no-bus --config "$tmp/weedspray.toml" --state-dir "$tmp/state" \
  --sim-images "$images" --run-seconds 6 >"$tmp/log" 2>&1 || { cat "$tmp/log"; fail "weedsprayd failed"; }
grep -q -- '-> Spraying' "$tmp/log" || { cat "$tmp/log"; fail "never sprayed"; }
# The status lines' duties ("duty  20  40 ..."): some nozzle opened for the plants it saw.
opened="$(sed -n 's/.* duty \(\( *[0-9]\+\)\+\) .*/\1/p' "$tmp/log" | tr -s ' ' '\n' | awk '$1 > 0' | wc -l)"
[ "$opened" -ge 1 ] || { cat "$tmp/log"; fail "no nozzle opened on the sample field in 6 s"; }
if grep -q 'alarm raised: camera' "$tmp/log"; then cat "$tmp/log"; fail "a camera alarm"; fi
echo "PASS: $count sample photos; $opened nozzle-duties above 0 in the status lines"
