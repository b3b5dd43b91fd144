#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Figures of the fleet (docs/benchmarks.md, "Fleet and cab"): three weedsprayd --sim boards
# spraying with their bridges on a loopback mosquitto, then the cab page serving 12 boards.
#  1. broker messages per second per board, and per topic, over 10 s of spraying;
#  2. command latency: "start" published on the machine's topic -> each daemon's state change
#     (its log's millisecond time stamps), over 5 stop/start cycles;
#  3. weedspray-cab's CPU and peak memory over 30 s with 12 boards (board 1's recorded messages
#     replayed as 12 boards by tools/fleet-replay.py) and the page open in headless Chromium.
#   tools/fleet-bench.sh [--json] [BUILD_DIR]     (default build/default)
# --json: the three figures as one JSON object instead of text.
# Uses the fleet tests' helpers (tests/integration/fleet/fleet_lib.sh).
set -euo pipefail
cd "$(dirname "$0")/.."
SOURCE=$(pwd)
JSON=0
if [ "${1:-}" = --json ]; then JSON=1; shift; fi
export JSON
BUILD=$(realpath "${1:-build/default}")
PY=/usr/bin/python3
. tests/integration/fleet/fleet_lib.sh fleet-bench
BOARDS=(1 2 3)

start_broker
make_green_field
for n in "${BOARDS[@]}"; do
  write_board_config "$n"
  start_board "$n"
done
for n in "${BOARDS[@]}"; do wait_board_state "$n" Idle 30; done
for n in "${BOARDS[@]}"; do start_bridge "$n"; done
for n in "${BOARDS[@]}"; do wait_retained "weedspray/$MACHINE/b$n/online" '^true$' 10; done

# 1. Messages while spraying (retained ones left out: -R; the live-view pictures too: binary
#    PNGs, one per fleet.picture_interval_s, that a line-based recording cannot hold).
publish "weedspray/$MACHINE/cmd" '{"command":"start"}'
for n in "${BOARDS[@]}"; do wait_board_state "$n" Spraying 2; done
sleep 2
mosquitto_sub -h 127.0.0.1 -p "$PORT" -t "weedspray/$MACHINE/+/+" \
  -T "weedspray/$MACHINE/+/picture" -v -R -W 10 2>/dev/null |
  $PY -c 'import sys, time
for line in sys.stdin: print(f"{time.time():.3f} {line}", end="", flush=True)' \
    >"$T/recording.txt" || true
$PY - "$T/recording.txt" "$T/figures-1.json" <<'PYEOF'
import collections, json, os, sys
boards, leaves = collections.Counter(), collections.Counter()
for line in open(sys.argv[1]):
    topic = line.split(" ", 2)[1].split("/")
    boards[topic[2]] += 1
    leaves[topic[3]] += 1
figures = {
    "messages_per_s_per_board": {b: n / 10 for b, n in sorted(boards.items())},
    "messages_per_s_per_topic": {l: n / 10 for l, n in sorted(leaves.items())},
    "payload_bytes_mean": round(sum(len(l.split(" ", 2)[2]) for l in open(sys.argv[1]))
                                / max(1, sum(boards.values())))}
json.dump(figures, open(sys.argv[2], "w"))
if os.environ["JSON"] != "1":
    print("messages/s per board over 10 s:", figures["messages_per_s_per_board"])
    print("messages/s per topic, all boards:", figures["messages_per_s_per_topic"])
    print("payload bytes/message, mean:", figures["payload_bytes_mean"])
PYEOF

# 2. Command latency: broker publish -> daemon state change.
: >"$T/latency.txt"
for cycle in 1 2 3 4 5; do
  publish "weedspray/$MACHINE/cmd" '{"command":"stop"}'
  for n in "${BOARDS[@]}"; do wait_board_state "$n" Idle 2; done
  sleep 0.5
  echo "$cycle $(now)" >>"$T/latency.txt"
  publish "weedspray/$MACHINE/cmd" '{"command":"start"}'
  for n in "${BOARDS[@]}"; do wait_board_state "$n" Spraying 2; done
done
$PY - "$T/latency.txt" "$T/figures-2.json" "$T"/daemon*.log <<'PYEOF'
import datetime, json, os, re, statistics, sys
sent = [float(l.split()[1]) for l in open(sys.argv[1])]
delays = []
for log in sys.argv[3:]:
    starts = [datetime.datetime.strptime(m.group(1), "%Y-%m-%d %H:%M:%S.%f").timestamp()
              for m in re.finditer(r"^\[([^\]]+)\] \[weedsprayd\] \[info\] state Idle -> Spraying \(Start\)",
                                   open(log).read(), re.M)]
    for t in sent:
        after = [s - t for s in starts if s >= t - 0.001]
        if after: delays.append(min(after) * 1000)
json.dump({"start_to_spraying_ms": {"median": round(statistics.median(delays), 1),
                                     "max": round(max(delays), 1), "n": len(delays)}},
          open(sys.argv[2], "w"))
if os.environ["JSON"] != "1":
    print(f"start published -> daemon Spraying: median {statistics.median(delays):.0f} ms, "
          f"max {max(delays):.0f} ms over {len(delays)} board starts (mosquitto_pub's own start included)")
PYEOF
publish "weedspray/$MACHINE/cmd" '{"command":"stop"}'
for n in "${BOARDS[@]}"; do kill -TERM "${BRIDGE_PID[$n]}" "${DAEMON_PID[$n]}"; done
sleep 1

# 3. The cab with 12 boards (board 1's stream replayed), the page open in Chromium.
grep " weedspray/$MACHINE/b1/" "$T/recording.txt" >"$T/b1.txt"
CAB_PORT=$($PY -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])')
printf '%s\n' "[fleet]" "port = $PORT" 'machine = "bench12"' "[cab]" "port = $CAB_PORT" >"$T/cab.toml"
"$BUILD/cab/weedspray-cab" --config "$T/cab.toml" >"$T/cab.log" 2>&1 &
cab_pid=$!
PIDS+=($cab_pid)
sleep 0.5
chromium --headless=new --no-sandbox --disable-gpu --no-first-run --user-data-dir="$T/chrome" \
  --remote-debugging-port=0 "http://127.0.0.1:$CAB_PORT/" >"$T/chromium.log" 2>&1 &
PIDS+=($!)
sleep 3
ticks() { awk '{print $14 + $15}' "/proc/$cab_pid/stat"; }
before=$(ticks)
sent=$($PY tools/fleet-replay.py "$PORT" bench12 12 30 "$T/b1.txt")
after=$(ticks)
boards_shown=$($PY "$SOURCE/tests/integration/fleet/cdp.py" "$T/chrome" 'document.querySelectorAll(".board").length')
hwm=$(awk '/VmHWM/ {print $2}' "/proc/$cab_pid/status")
hz=$(getconf CLK_TCK)
$PY - "$((after - before))" "$hz" "$hwm" "$sent" "$boards_shown" "$T"/figures-*.json <<'PYEOF'
import json, os, sys
t, hz, kb, sent, shown = map(float, sys.argv[1:6])
cab = {"boards": 12, "messages_per_s_in": round(sent / 30, 1), "boards_shown": int(shown),
       "cpu_pct_of_one_core": round(100 * t / hz / 30, 2), "peak_rss_mb": round(kb / 1024, 1)}
if os.environ["JSON"] == "1":
    figures = {}
    for part in sys.argv[6:]:
        figures.update(json.load(open(part)))
    print(json.dumps(dict(figures, cab=cab)))
else:
    print(f"weedspray-cab, 12 boards ({cab['messages_per_s_in']:.0f} messages/s in, page polling "
          f"4/s, {shown:.0f} boards shown): CPU {cab['cpu_pct_of_one_core']:.1f} % of one core, "
          f"peak resident {cab['peak_rss_mb']:.1f} MB")
PYEOF
