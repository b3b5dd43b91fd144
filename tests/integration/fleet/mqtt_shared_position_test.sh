#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Shared position over a loopback mosquitto: board 1 owns the speed and the position ([gnss] on
# a real gpsd that gpsfake feeds the recorded track, speed.source = "gnss" so that the shared
# speed is the track's, fleet.motion_rate_hz = 20); board 2 has no receiver and takes both (speed.source = "fleet",
# gnss.source = "fleet", its boom section's centre 3 m right of board 1's antenna). Both spray
# while the track plays; board 2's as-applied log then holds positions that follow board 1's
# (the antenna within 0.5 m of board 1's at the same UTC time) and its middle nozzle's patch
# 3 m right of the antenna across the heading. gpsfake stopped: board 1 shares no fix any more
# and board 2 raises gnss_fix_lost.
# usage: mqtt_shared_position_test.sh BUILD_DIR SOURCE_DIR
set -euo pipefail
BUILD=$(realpath "$1")
SOURCE=$(realpath "$2")
PY=/usr/bin/python3
. "$(dirname "$0")/fleet_lib.sh" shared-position
EXIT_HOOKS=()
. "$SOURCE/tests/integration/daemon/gpsfake_lib.sh"
trap 'stop_gpsfake; cleanup' EXIT
require_gpsfake
BOARDS=(1 2)

start_broker
make_green_field
GPSD_PORT=$(free_port)
write_board_config 1 'motion_rate_hz = 20' '[speed]' 'source = "gnss"' '[gnss]' \
  'enabled = true' 'host = "127.0.0.1"' "port = $GPSD_PORT" 'lost_fix_timeout_s = 2.0' \
  'first_fix_timeout_s = 60.0' 'reconnect_max_s = 0.25'
write_board_config 2 'speed_from = "b1"' '[speed]' 'source = "fleet"' '[gnss]' \
  'enabled = true' 'source = "fleet"' 'lost_fix_timeout_s = 2.0' 'first_fix_timeout_s = 60.0' \
  'antenna_right_of_centre_m = -3.0'
for n in "${BOARDS[@]}"; do start_board "$n"; done
for n in "${BOARDS[@]}"; do wait_board_state "$n" Idle 30; done
for n in "${BOARDS[@]}"; do start_bridge "$n"; done
wait_board_prop 2 SpeedSource '"fleet"' 10

# The track once, 0.1 s a sentence (0.3 s an epoch, ~10 s in all); -W: gpsfake ends 2 s after.
start_gpsfake "$GPSD_PORT" "$T/gpsfake.log" -1 -q -c 0.1 -W 2 \
  "$SOURCE/tests/data/gnss/field_track.nmea"
wait_board_prop 1 GnssFix '"3d"' 15
wait_board_prop 2 GnssFix '"3d"' 5
echo "ok: board 2, without a receiver, has board 1's 3d fix"
publish "weedspray/$MACHINE/cmd" '{"command":"start","id":"go"}'
wait_board_state 1 Spraying 5
wait_board_state 2 Spraying 5
echo "ok: both boards spraying"

# The track's stop (14:30:27 on its clock), then gpsd gone: board 1's fix ages out, so it
# shares none, and board 2 loses its fix too.
for _ in $(seq 1 300); do
  [[ "$(board_prop 1 GnssTime)" > '"2026-06-24T14:30:27' ]] && break
  sleep 0.1
done
[[ "$(board_prop 1 GnssTime)" > '"2026-06-24T14:30:27' ]] ||
  fail "the track's stop never came: board 1's GnssTime $(board_prop 1 GnssTime)"
t0=$(now)
stop_gpsfake
for _ in $(seq 1 100); do
  [[ "$(board_prop 2 Alarms)" == *'"gnss_fix_lost"'* ]] && break
  sleep 0.1
done
[[ "$(board_prop 2 Alarms)" == *'"gnss_fix_lost"'* ]] ||
  fail "board 2 never raised gnss_fix_lost: $(board_prop 2 Alarms)"
[ "$(board_prop 2 GnssFix)" = '"none"' ] || fail "board 2's GnssFix: $(board_prop 2 GnssFix)"
echo "ok: board 2 raised gnss_fix_lost $(elapsed_since "$t0") s after gpsd stopped (timeout 2 s)"

for n in "${BOARDS[@]}"; do kill -TERM "${DAEMON_PID[$n]}"; done
for n in "${BOARDS[@]}"; do wait "${DAEMON_PID[$n]}" || fail "board $n exit status $?"; done
$PY - "$T/b1/state/as-applied" "$T/b2/state/as-applied" <<'PYEOF' || fail "board 2's positions"
import csv, glob, math, sys
from datetime import datetime

R = 6371008.8

def rows(folder):
    out = []
    for path in sorted(glob.glob(folder + "/*.csv")):
        for r in csv.DictReader(open(path)):
            if r["latitude_deg"] and r["utc"]:
                t = datetime.strptime(r["utc"], "%Y-%m-%dT%H:%M:%S.%fZ").timestamp()
                out.append((t, r))
    return out

def north_east(a, b):  # metres from a to b (lat, lon)
    n = math.radians(b[0] - a[0]) * R
    e = math.radians(b[1] - a[1]) * R * math.cos(math.radians(a[0]))
    return n, e

owner, taker = rows(sys.argv[1]), rows(sys.argv[2])
assert len(owner) > 20, f"board 1 logged {len(owner)} positioned records"
assert len(taker) > 20, f"board 2 logged {len(taker)} positioned records (none: no shared fix)"
worst = 0.0
across = []
for t, r in taker:
    later = next((i for i, (u, _) in enumerate(owner) if u >= t), None)
    if later is None or later == 0:
        continue
    (t0, a), (t1, b) = owner[later - 1], owner[later]
    if t1 - t0 > 0.5:
        continue
    f = (t - t0) / (t1 - t0) if t1 > t0 else 0.0
    lat = float(a["latitude_deg"]) + f * (float(b["latitude_deg"]) - float(a["latitude_deg"]))
    lon = float(a["longitude_deg"]) + f * (float(b["longitude_deg"]) - float(a["longitude_deg"]))
    here = (float(r["latitude_deg"]), float(r["longitude_deg"]))
    worst = max(worst, math.hypot(*north_east((lat, lon), here)))
    if r["course_deg"] and r["latitude_deg_1"]:
        n, e = north_east(here, (float(r["latitude_deg_1"]), float(r["longitude_deg_1"])))
        h = math.radians(float(r["course_deg"]))
        across.append(e * math.cos(h) - n * math.sin(h))  # right of the heading
assert worst < 0.5, f"board 2's antenna {worst:.3f} m from board 1's at the same time"
assert across, "board 2 placed no nozzle"
off = max(abs(x - 3.0) for x in across)
assert off < 0.05, f"board 2's middle nozzle {min(across):.3f}..{max(across):.3f} m right, not 3"
print(f"ok: board 2 logged {len(taker)} positioned records (board 1 {len(owner)}); its antenna "
      f"at most {worst:.3f} m from board 1's at the same UTC time; its middle nozzle "
      f"{sum(across) / len(across):.3f} m right of it (worst {off:.3f} m off 3 m)")
PYEOF
