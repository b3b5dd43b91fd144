#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The D-Bus policy file on a private bus that loads it (like the system bus does), its three
# permissions: anyone (here: nobody, in no group) may read properties and introspect, but every
# method call is denied; an operator (group weedspray) may start, stop, set the pressure, the
# decision threshold and the dose, and clear alarms, not reload or calibrate; an engineer (group weedspray-admin) and root may call
# every method. The policy's two groups are mapped to groups every Debian has (users, staff),
# so that the test needs no group of its own on the machine. Also: a malformed policy is
# rejected by dbus-daemon, so the file is known to parse.
# usage: bus_policy_test.sh BUILD_DIR SOURCE_DIR   (runs as root; skipped otherwise)
set -euo pipefail
BUILD=$(realpath "$1")
SOURCE=$(realpath "$2")
POLICY=$SOURCE/systemd/org.weedspray.Sprayer1.conf
if [ "$(id -u)" -ne 0 ] || ! id nobody >/dev/null 2>&1; then
  echo "SKIP: needs root and user nobody"
  exit 0
fi
. "$(dirname "$0")/private_bus_lib.sh" policy
chmod 755 "$T"

write_bus_config() {  # write_bus_config POLICY_FILE OUTPUT
  cat >"$2" <<XML
<!DOCTYPE busconfig PUBLIC "-//freedesktop//DTD D-BUS Bus Configuration 1.0//EN"
 "http://www.freedesktop.org/standards/dbus/1.0/busconfig.dtd">
<busconfig>
  <type>custom</type>
  <listen>unix:path=$T/bus</listen>
  <auth>EXTERNAL</auth>
  <!-- the system bus's defaults: deny owning and sending unless a policy allows it -->
  <policy context="default">
    <allow user="*"/>
    <deny own="*"/>
    <deny send_type="method_call"/>
    <allow send_destination="org.freedesktop.DBus"/>
    <allow send_type="signal"/>
    <allow send_requested_reply="true" send_type="method_return"/>
    <allow send_requested_reply="true" send_type="error"/>
    <allow receive_type="method_call"/>
    <allow receive_type="method_return"/>
    <allow receive_type="error"/>
    <allow receive_type="signal"/>
  </policy>
  <include>$1</include>
</busconfig>
XML
}

# A malformed policy must not load.
sed 's/send_destination/sned_destination/' "$POLICY" >"$T/bad.conf"
write_bus_config "$T/bad.conf" "$T/bad-bus.conf"
if dbus-daemon --config-file="$T/bad-bus.conf" --fork --nopidfile --print-address=1 \
  >/dev/null 2>&1; then
  fail "dbus-daemon accepted a malformed policy (the check cannot tell good from bad)"
fi

sed -e 's/group="weedspray-admin"/group="staff"/' -e 's/group="weedspray"/group="users"/' \
  "$POLICY" >"$T/policy.conf"
grep -q 'group="users"' "$T/policy.conf" && grep -q 'group="staff"' "$T/policy.conf" ||
  fail "the policy names neither group weedspray nor weedspray-admin"
write_bus_config "$T/policy.conf" "$T/bus.conf"
dbus-daemon --config-file="$T/bus.conf" --fork --nopidfile --print-address=3 --print-pid=4 \
  3>"$T/bus.addr" 4>"$T/bus.pid" 2>"$T/bus.err" || fail "bus: $(cat "$T/bus.err")"
BUS_PID=$(cat "$T/bus.pid")
export DBUS_SESSION_BUS_ADDRESS=$(cat "$T/bus.addr")
chmod 777 "$T/bus"

mkdir -p "$T/state"
"$BUILD/daemon/weedsprayd" --sim --user --config "$SOURCE/etc/weedspray.toml" \
  --state-dir "$T/state" >"$T/daemon.log" 2>&1 &
DAEMON_PID=$!
as_nobody() { setpriv --reuid=nobody --regid=nogroup --clear-groups "$@"; }
as_operator() { setpriv --reuid=nobody --regid=nogroup --groups=users "$@"; }
as_engineer() { setpriv --reuid=nobody --regid=nogroup --groups=staff "$@"; }
denied() {  # denied WHO SPRAYCTL_ARGS...: the bus refuses the call
  local who=$1
  shift
  if "$who" "$BUILD/daemon/sprayctl" --user "$@" 2>"$T/err.txt"; then fail "$who: $* allowed"; fi
  grep -q "AccessDenied" "$T/err.txt" || fail "$who: $*: $(cat "$T/err.txt")"
}
passed_by_the_bus() {  # passed_by_the_bus WHO METHOD [SIGNATURE ARGS...]: the call reaches the
  # daemon (which may still refuse it for its state)
  local who=$1
  shift
  "$who" busctl --user call org.weedspray.Sprayer1 /org/weedspray/Sprayer1 \
    org.weedspray.Sprayer1 "$@" >/dev/null 2>"$T/err.txt" || true
  # busctl words the refusal "Access denied"; sd-bus clients name it AccessDenied.
  if grep -Eq "AccessDenied|Access denied" "$T/err.txt"; then
    fail "$who: $* denied: $(cat "$T/err.txt")"
  fi
}
state() { busctl --user get-property org.weedspray.Sprayer1 /org/weedspray/Sprayer1 \
  org.weedspray.Sprayer1 State; }
for _ in $(seq 1 100); do
  state=$(busctl --user get-property org.weedspray.Sprayer1 /org/weedspray/Sprayer1 \
    org.weedspray.Sprayer1 State 2>/dev/null || true)
  [ "$state" = 's "Idle"' ] && break
  kill -0 "$DAEMON_PID" 2>/dev/null || fail "weedsprayd could not start on the policy bus"
  sleep 0.2
done

# Anyone reads and introspects.
as_nobody busctl --user get-property org.weedspray.Sprayer1 /org/weedspray/Sprayer1 \
  org.weedspray.Sprayer1 State >"$T/out.txt" 2>&1 || fail "nobody cannot read State: $(cat "$T/out.txt")"
as_nobody "$BUILD/daemon/sprayctl" --user status --json >"$T/out.txt" 2>&1 ||
  fail "nobody cannot GetAll: $(cat "$T/out.txt")"
as_nobody busctl --user introspect org.weedspray.Sprayer1 /org/weedspray/Sprayer1 >/dev/null 2>&1 ||
  fail "nobody cannot introspect"
echo "ok: reading allowed to everyone"

# Methods: denied to nobody, allowed to root.
for cmd in start stop clear-alarms reload "set-pressure 0.3" "set-threshold 0.2" "set-rate 150" \
  "calibrate nozzles" "calibrate meter --seconds 5"; do
  # shellcheck disable=SC2086
  denied as_nobody $cmd
done
if as_nobody busctl --user set-property org.weedspray.Sprayer1 /org/weedspray/Sprayer1 \
  org.weedspray.Sprayer1 State s Spraying 2>/dev/null; then
  fail "nobody could Set a property"
fi
echo "ok: methods denied to other users"

# An operator operates: start, set the pressure, the threshold and the dose, clear alarms, stop;
# reloading and calibrating are refused.
as_operator "$BUILD/daemon/sprayctl" --user start 2>"$T/err.txt" || fail "operator: start: $(cat "$T/err.txt")"
[ "$(state)" = 's "Spraying"' ] || fail "the operator's Start had no effect: $(state)"
as_operator "$BUILD/daemon/sprayctl" --user set-pressure 0.3 || fail "operator: set-pressure"
as_operator "$BUILD/daemon/sprayctl" --user set-threshold 0.2 || fail "operator: set-threshold"
as_operator "$BUILD/daemon/sprayctl" --user set-rate 150 || fail "operator: set-rate"
as_operator "$BUILD/daemon/sprayctl" --user clear-alarms || fail "operator: clear-alarms"
as_operator "$BUILD/daemon/sprayctl" --user stop || fail "operator: stop"
[ "$(state)" = 's "Idle"' ] || fail "the operator's Stop had no effect: $(state)"
for cmd in reload "calibrate nozzles" "calibrate meter --seconds 5" "calibrate meter --volume 1"; do
  # shellcheck disable=SC2086
  denied as_operator $cmd
done
if as_operator busctl --user call org.weedspray.Sprayer1 /org/weedspray/Sprayer1 \
  org.weedspray.Sprayer1 InjectSimFault s pump_stops@1 2>/dev/null; then
  fail "an operator could inject a simulated fault"
fi
# The fleet bridge (group weedspray) reads and feeds the ground speed and position shared
# between boards; nobody else may feed them.
passed_by_the_bus as_operator Motion
passed_by_the_bus as_operator FeedSharedMotion ddt 1.5 10 1000
passed_by_the_bus as_operator MotionWithFix
passed_by_the_bus as_operator FeedSharedMotionWithFix ddtdddutx 1.5 10 1000 52 5 90 3 900 0
as_nobody busctl --user call org.weedspray.Sprayer1 /org/weedspray/Sprayer1 \
  org.weedspray.Sprayer1 FeedSharedMotion ddt 1.5 10 1000 >"$T/err.txt" 2>&1 || true
grep -Eq "AccessDenied|Access denied" "$T/err.txt" ||
  fail "nobody could feed a shared speed sample: $(cat "$T/err.txt")"
as_nobody busctl --user call org.weedspray.Sprayer1 /org/weedspray/Sprayer1 \
  org.weedspray.Sprayer1 FeedSharedMotionWithFix ddtdddutx 1.5 10 1000 52 5 90 3 900 0 \
  >"$T/err.txt" 2>&1 || true
grep -Eq "AccessDenied|Access denied" "$T/err.txt" ||
  fail "nobody could feed a shared position sample: $(cat "$T/err.txt")"
echo "ok: an operator may operate, not reload or calibrate"

"$BUILD/daemon/sprayctl" --user start || fail "root cannot Start"
[ "$(busctl --user get-property org.weedspray.Sprayer1 /org/weedspray/Sprayer1 \
  org.weedspray.Sprayer1 State)" = 's "Spraying"' ] || fail "root's Start had no effect"
echo "ok: root may call methods"

# An engineer may reload and calibrate as well.
as_engineer "$BUILD/daemon/sprayctl" --user reload 2>"$T/err.txt" || fail "engineer: reload: $(cat "$T/err.txt")"
passed_by_the_bus as_engineer CalibrateMeter d 5
passed_by_the_bus as_engineer CalibrateNozzles
passed_by_the_bus as_engineer CalibrateWheel d 20
echo "ok: an engineer may reload and calibrate"
kill -TERM "$DAEMON_PID"
wait "$DAEMON_PID" || fail "exit status $? after SIGTERM"
DAEMON_PID=
echo "PASS"
