#!/usr/bin/env bash
# Real-time timing of the simulated sprayer: runs `weedsprayd --sim` on a private session bus,
# starts spraying, optionally loads the machine with stress-ng, and prints the daemon's timing
# report (per loop: p50/p99/p99.9/max lateness in microseconds, misses beyond
# alarms.timing_tolerance_ms, overruns) plus the alarms raised. Run as root for SCHED_FIFO.
#   tools/rt-timing.sh [--seconds N] [--stress] [--no-qos] [--build DIR]
# --stress: stress-ng --cpu 2 --io 1 --vm 1 for the whole run (Debian's stress-ng)
# --no-qos: daemon.cpu_wakeup_latency_us = -1 (no PM QoS request), to see what it fixes
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=60 stress=0 qos=1 build=build/default
while (($#)); do
  case "$1" in
    --seconds) seconds="$2"; shift ;;
    --stress) stress=1 ;;
    --no-qos) qos=0 ;;
    --build) build="$2"; shift ;;
    *) sed -n '2,9p' "$0"; exit 2 ;;
  esac
  shift
done
tmp=$(mktemp -d)
trap 'kill $(jobs -p) 2>/dev/null || true; rm -rf "$tmp"' EXIT
cp etc/weedspray.toml "$tmp/weedspray.toml"
mkdir -p "$tmp/conf.d"
[ "$qos" = 1 ] || printf '[daemon]\ncpu_wakeup_latency_us = -1\n' >"$tmp/conf.d/no-qos.toml"
if [ "$stress" = 1 ]; then
  command -v stress-ng >/dev/null || { echo "rt-timing: stress-ng missing (apt-get install stress-ng)" >&2; exit 1; }
  stress-ng --cpu 2 --io 1 --vm 1 --timeout "$((seconds + 15))s" >/dev/null 2>&1 &
fi
export DBUS_SESSION_BUS_ADDRESS="unix:path=$tmp/bus"
dbus-daemon --session --address="$DBUS_SESSION_BUS_ADDRESS" --fork --print-pid >"$tmp/bus.pid"
trap 'kill $(cat "$tmp/bus.pid") $(jobs -p) 2>/dev/null || true; rm -rf "$tmp"' EXIT
"$build/daemon/weedsprayd" --sim --user --config "$tmp/weedspray.toml" --state-dir "$tmp/state" \
  --run-seconds "$((seconds + 3))" --timing-report "$tmp/timing.json" >"$tmp/daemon.log" 2>&1 &
daemon=$!
for _ in $(seq 100); do
  "$build/daemon/sprayctl" --user start >/dev/null 2>&1 && break
  sleep 0.1
done
wait "$daemon" || { cat "$tmp/daemon.log" >&2; exit 1; }
alarms=$( (grep -o 'alarm raised: [a-z_]*' "$tmp/daemon.log" || true) | sort | uniq -c | tr -s ' ' | paste -sd, -)
printf '{"stress": %s, "pm_qos": %s, "alarms": "%s", "timing": %s}\n' \
  "$([ "$stress" = 1 ] && echo true || echo false)" "$([ "$qos" = 1 ] && echo true || echo false)" \
  "${alarms# }" "$(cat "$tmp/timing.json")"
