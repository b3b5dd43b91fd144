#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# weedsprayd --sim as a newcomer runs it: no configuration file -> the built-in defaults (said
# so); its records go to the user's sim state folder, never daemon.state_dir (the sprayer's);
# a second run starts from zero unless --resume. Hardware mode without its file stays an error.
set -euo pipefail
BUILD=$1
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
fail() { echo "FAIL: $*"; cat "$T"/*.log 2>/dev/null; exit 1; }
cd "$T"
export HOME="$T/home" && unset XDG_STATE_HOME
mkdir -p "$HOME"
"$BUILD/daemon/weedsprayd" --sim --no-bus --run-seconds 1 >"$T/first.log" 2>&1 || fail "sim run"
grep -q "simulating on the built-in defaults" "$T/first.log" || fail "defaults not said"
state="$HOME/.local/state/weedspray-sim"
[ -f "$state/totals.toml" ] || fail "no totals in $state"
ls "$state/as-applied"/as-applied-*.csv >/dev/null || fail "no as-applied log in $state"
grep -q "totals start from zero" "$T/first.log" || fail "first run did not start from zero"
# The configured daemon.state_dir (a folder that must stay untouched) is not used in sim.
mkdir -p "$T/records"
printf "[daemon]\nstate_dir = '%s'\n" "$T/records" >"$T/weedspray.toml"
"$BUILD/daemon/weedsprayd" --sim --no-bus --run-seconds 1 --config "$T/weedspray.toml" \
  >"$T/second.log" 2>&1 || fail "sim run with a config"
[ -z "$(ls -A "$T/records")" ] || fail "sim wrote the sprayer's records: $(ls "$T/records")"
"$BUILD/daemon/weedsprayd" --sim --no-bus --run-seconds 1 --resume >"$T/third.log" 2>&1 ||
  fail "sim --resume"
grep -q "totals start from zero" "$T/third.log" && fail "--resume started from zero"
# A named file that does not exist is an error, in sim too; hardware mode needs its file.
if "$BUILD/daemon/weedsprayd" --sim --no-bus --run-seconds 1 --config "$T/missing.toml" \
  >"$T/missing.log" 2>&1; then fail "a missing --config was accepted"; fi
grep -q "missing.toml" "$T/missing.log" || fail "the missing file is not named"
if "$BUILD/daemon/weedsprayd" --no-bus --run-seconds 1 --config "$T/missing.toml" \
  >"$T/hw.log" 2>&1; then fail "hardware mode ran without its file"; fi
echo "ok: sim on defaults, records in $state, --resume, missing files named"
