#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Resident memory of the simulated sprayer: runs `weedsprayd --sim --no-bus` spraying for N
# seconds with one or four cameras (1280x800, the default camera) and the vegetation or dnn
# weed source (the default model), and prints one JSON line per case: the peak resident set
# (VmHWM), the resident set at the end (VmRSS), the RAM of it that is locked (smaps_rollup's
# Locked) and the address space marked locked (VmLck: it counts untouched heap and stacks that
# are locked only as they are first used), in MB.
#   tools/memory-bench.sh [--seconds N] [--build DIR]
# The daemon locks the program and the libraries its real-time loops run (read in at start) and
# its heap and stacks as they are used; the vision thread's libraries (OpenCV, BLAS) stay
# pageable. The resident figure is what the board must have free.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=20 build=build/default
while (($#)); do
  case "$1" in
    --seconds) seconds="$2"; shift ;;
    --build) build="$2"; shift ;;
    *) sed -n '2,8p' "$0"; exit 2 ;;
  esac
  shift
done
tmp=$(mktemp -d)
trap 'kill $(jobs -p) 2>/dev/null || true; rm -rf "$tmp"' EXIT

config() { # CAMERAS SOURCE -> a configuration file
  local cameras="$1" source="$2" file="$tmp/$1-$2.toml"
  printf '[daemon]\nautostart = true\n[boom]\nnozzles = %d\n[vision]\nweed_source = "%s"\n' \
    "$((cameras * 2))" "$source" >"$file"
  for ((c = 0; c < cameras; c++)); do
    printf '[[camera]]\nfirst_nozzle = %d\nnozzle_count = 2\nwidth = 1280\nheight = 800\n' \
      "$((c * 2))" >>"$file"
  done
  echo "$file"
}
kb_to_mb() { awk -v kb="$1" 'BEGIN { printf "%.1f", kb / 1024 }'; }
field() { awk -v k="$1:" '$1 == k { print $2 }' "$2"; }

for cameras in 1 4; do
  for source in vegetation dnn; do
    file="$(config "$cameras" "$source")"
    "$build/daemon/weedsprayd" --sim --no-bus --config "$file" --state-dir "$tmp/state-$cameras-$source" \
      --run-seconds "$seconds" >"$tmp/daemon.log" 2>&1 &
    daemon=$!
    # The last status before the daemon ends: VmHWM is the peak since start.
    while kill -0 "$daemon" 2>/dev/null; do
      cp "/proc/$daemon/status" "$tmp/status.new" 2>/dev/null || true
      cp "/proc/$daemon/smaps_rollup" "$tmp/rollup.new" 2>/dev/null || true
      ! grep -q '^VmHWM:' "$tmp/status.new" 2>/dev/null || mv "$tmp/status.new" "$tmp/status"
      ! grep -q '^Locked:' "$tmp/rollup.new" 2>/dev/null || mv "$tmp/rollup.new" "$tmp/rollup"
      sleep 0.5
    done
    wait "$daemon" || { cat "$tmp/daemon.log" >&2; exit 1; }
    spraying="$(grep -c -- '-> Spraying' "$tmp/daemon.log" || true)"
    printf '{"cameras": %d, "weed_source": "%s", "seconds": %d, "sprayed": %s, "peak_rss_mb": %s, "rss_mb": %s, "locked_mb": %s, "locked_address_space_mb": %s}\n' \
      "$cameras" "$source" "$seconds" "$([ "$spraying" -ge 1 ] && echo true || echo false)" \
      "$(kb_to_mb "$(field VmHWM "$tmp/status")")" "$(kb_to_mb "$(field VmRSS "$tmp/status")")" \
      "$(kb_to_mb "$(field Locked "$tmp/rollup")")" "$(kb_to_mb "$(field VmLck "$tmp/status")")"
  done
done
