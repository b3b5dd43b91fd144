#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# No spraying by itself after a run that did not end in order: the simulated sprayer with
# daemon.autostart sprays; killed with SIGKILL, the next start (the same state folder) waits
# for Start and says why; after that run ends in order, autostart sprays again.
# usage: unfinished_run_sim_test.sh BUILD_DIR
set -euo pipefail
BUILD=$(realpath "$1")
. "$(dirname "$0")/private_bus_lib.sh" unfinished-run  # $T and fail(); no bus is started
FAIL_LOGS=("$T/first.log" "$T/after_kill.log" "$T/after_orderly_stop.log")
write_sim_config
resumed_sim first &
DAEMON_PID=$!
wait_log "$T/first.log" "state Idle -> Spraying"
kill -KILL "$DAEMON_PID"
wait "$DAEMON_PID" 2>/dev/null || true
DAEMON_PID=

(resumed_sim after_kill --run-seconds 4) || fail "after_kill: exit status $?"
grep -q "the last run did not end in an orderly stop" "$T/after_kill.log" ||
  fail "after_kill: no word of the unfinished run"
grep -q "daemon.autostart skipped" "$T/after_kill.log" || fail "after_kill: autostart not skipped"
if grep -q "state Idle -> Spraying" "$T/after_kill.log"; then
  fail "after_kill: sprayed by itself after a kill -9"
fi

(resumed_sim after_orderly_stop --run-seconds 4) || fail "after_orderly_stop: exit status $?"
grep -q "state Idle -> Spraying" "$T/after_orderly_stop.log" ||
  fail "after_orderly_stop: autostart did not spray after an orderly stop"
echo "ok: kill -9 -> the next start waits for Start; an orderly stop -> autostart sprays"
