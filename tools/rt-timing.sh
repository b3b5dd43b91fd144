#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Real-time timing of the simulated sprayer: runs `weedsprayd --sim` on a private session bus,
# starts spraying, optionally loads the machine with stress-ng, and prints the daemon's timing
# report (per loop: p50/p99/p99.9/max lateness in microseconds, misses beyond
# alarms.timing_tolerance_ms, overruns) plus the alarms raised. Run as root for SCHED_FIFO.
#   tools/rt-timing.sh [--seconds N] [--stress] [--no-qos] [--reference] [--build DIR]
# --stress: stress-ng --cpu 2 --io 1 --vm 1 for the whole run (Debian's stress-ng)
# --no-qos: daemon.cpu_wakeup_latency_us = -1 (no PM QoS request), to see what it fixes
# --reference: cyclictest (Debian's rt-tests) beside the daemon, one thread per CPU at 1 kHz,
#   SCHED_FIFO 79 (just under the valve thread's 80): the kernel's own wake-up latency under the
#   same load, so a late wake of the daemon can be told from a late wake of any thread
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=60 stress=0 qos=1 reference=0 build=build/default
while (($#)); do
  case "$1" in
    --seconds) seconds="$2"; shift ;;
    --stress) stress=1 ;;
    --no-qos) qos=0 ;;
    --reference) reference=1 ;;
    --build) build="$2"; shift ;;
    *) sed -n '2,12p' "$0"; exit 2 ;;
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
if [ "$reference" = 1 ]; then
  command -v cyclictest >/dev/null || { echo "rt-timing: cyclictest missing (apt-get install rt-tests)" >&2; exit 1; }
  cyclictest -m -q -p 79 -t "$(nproc)" -a -i 1000 -D "$seconds" >"$tmp/cyclictest.txt" 2>&1 &
  cyclictest_pid=$!
fi
wait "$daemon" || { cat "$tmp/daemon.log" >&2; exit 1; }
reference_json=null
if [ "$reference" = 1 ]; then
  wait "$cyclictest_pid" || true
  # "T: 0 ( 123) P:79 I:1000 C: 60000 Min: 3 Act: 20 Avg: 30 Max: 2592" per CPU
  reference_json=$(awk '/^T:/{for(i=1;i<=NF;i++){if($i=="Avg:")a=$(i+1);if($i=="Max:")m=$(i+1);if($i=="C:")c=$(i+1)}
    printf "%s{\"cpu\": %d, \"wakes\": %d, \"avg_us\": %d, \"max_us\": %d}", n++?", ":"", $2, c, a, m}' \
    "$tmp/cyclictest.txt")
  reference_json="[$reference_json]"
fi
alarms=$( (grep -o 'alarm raised: [a-z_]*' "$tmp/daemon.log" || true) | sort | uniq -c | tr -s ' ' | paste -sd, -)
printf '{"stress": %s, "pm_qos": %s, "alarms": "%s", "cyclictest": %s, "timing": %s}\n' \
  "$([ "$stress" = 1 ] && echo true || echo false)" "$([ "$qos" = 1 ] && echo true || echo false)" \
  "${alarms# }" "$reference_json" "$(cat "$tmp/timing.json")"
