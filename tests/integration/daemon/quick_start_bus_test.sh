#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The quick start as a newcomer runs it on a fresh machine as root (no session bus): the
# simulated daemon under tools/with-session-bus.sh (what `./dev sim` runs) prints one line, once
# the sprayer answers (after its start-up lines);
# pasted into another shell, `sprayctl --user status` shows the live sprayer with no alarm and
# nothing unreadable.
set -euo pipefail
BUILD=$1
SOURCE=$2
T=$(mktemp -d)
pid=
trap '[ -n "$pid" ] && kill "$pid" 2>/dev/null; rm -rf "$T"' EXIT
fail() { echo "FAIL: $*"; cat "$T/out.txt" 2>/dev/null; exit 1; }
cd "$SOURCE"
env -u DBUS_SESSION_BUS_ADDRESS XDG_RUNTIME_DIR="$T" tools/with-session-bus.sh \
  "$BUILD/daemon/weedsprayd" --sim --user --config etc/weedspray.toml --state-dir "$T/state" \
  --run-seconds 15 >"$T/out.txt" 2>&1 &
pid=$!
line=
for _ in $(seq 1 100); do
  line=$(grep -m1 "^  export DBUS_SESSION_BUS_ADDRESS=" "$T/out.txt" || true)
  [ -n "$line" ] && break
  sleep 0.1
done
[ -n "$line" ] || fail "no line to paste was printed"
# It comes once the sprayer answers: after the daemon's start-up lines, not above them.
grep -n -m1 "^  export DBUS_SESSION_BUS_ADDRESS=" "$T/out.txt" | cut -d: -f1 >"$T/line_no" || true
grep -n -m1 "weedsprayd running" "$T/out.txt" | cut -d: -f1 >"$T/running_no" || true
[ -s "$T/running_no" ] && [ "$(cat "$T/line_no")" -gt "$(cat "$T/running_no")" ] ||
  fail "the line to paste came before the daemon's start-up lines"
[ "$(grep -c "DBUS_SESSION_BUS_ADDRESS=" "$T/out.txt")" = 1 ] || fail "the line was printed twice"
# "Another shell": a clean environment with only what the printed line gives it.
status=
for _ in $(seq 1 100); do
  status=$(env -i PATH="$PATH" bash -c "${line#  }" 2>&1 || true)
  echo "$status" | grep -q "^State: *Idle" && break
  sleep 0.2
done
echo "$status"
echo "$status" | grep -q "^State: *Idle (sim)" || fail "sprayctl status: $status"
echo "$status" | grep -q "^Alarms: *none" || fail "the first screen carries an alarm"
# Nothing a newcomer cannot read: a subsystem that is off says so, no "nan" placeholders.
echo "$status" | grep -q "^GNSS: *off (gnss.enabled = false)$" || fail "GNSS line: $status"
if echo "$status" | grep -qi "nan"; then fail "the first screen shows nan"; fi
echo "ok: the printed line reaches the simulated sprayer; Idle, no alarm"
