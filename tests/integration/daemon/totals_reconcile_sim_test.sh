#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Totals reconciled from the as-applied log at start: the simulated sprayer sprays and is
# killed with SIGKILL before it saves its totals again (every 60 s); the next start adds the
# volume its log holds after the saved totals, so the totals equal the log's sum.
# usage: totals_reconcile_sim_test.sh BUILD_DIR
set -euo pipefail
BUILD=$(realpath "$1")
. "$(dirname "$0")/private_bus_lib.sh" totals-reconcile  # $T and fail(); no bus is started
FAIL_LOGS=("$T/first.log" "$T/second.log")
write_sim_config
# log_volume: the volume_l column summed over every as-applied file.
log_volume() {
  awk -F, '/^time_s,/ { next } { sum += $6 } END { printf "%.6f\n", sum }' \
    "$T"/state/as-applied/as-applied-*.csv
}
saved_volume() { sed -n 's/^volume_l = //p' "$T/state/totals.toml"; }

resumed_sim first &
DAEMON_PID=$!
wait_log "$T/first.log" "state Idle -> Spraying"
sleep 4  # a few seconds of records, fdatasync'd once a second
kill -KILL "$DAEMON_PID"
wait "$DAEMON_PID" 2>/dev/null || true
DAEMON_PID=
sprayed=$(log_volume)
awk -v v="$sprayed" 'BEGIN { exit !(v > 0.001) }' || fail "first: nothing sprayed ($sprayed L)"
awk -v s="$(saved_volume)" -v v="$sprayed" 'BEGIN { exit !(s < v / 2) }' ||
  fail "the totals were saved after spraying: nothing left to reconcile"

(resumed_sim second --run-seconds 1) || fail "second run"
grep -q "totals: [0-9.]* L added from [0-9]* as-applied records" "$T/second.log" ||
  fail "second: the log's volume was not added"
total=$(saved_volume)
logged=$(log_volume)
awk -v t="$total" -v l="$logged" 'BEGIN { d = t - l; exit !(d < 1e-4 && d > -1e-4) }' ||
  fail "totals $total L, the log $logged L"
# A third start finds nothing more to add: no volume counted twice.
(resumed_sim third --run-seconds 1) || fail "third run"
grep -q "L added from" "$T/third.log" && fail "third: volume added again"
echo "ok: $logged L in the log; the totals after a SIGKILL reconciled to $total L"
