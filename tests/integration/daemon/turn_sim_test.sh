#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Turn compensation and the GNSS wheel calibration, end to end: weedsprayd --sim with an
# 8-nozzle, 4 m boom on a real gpsd fed by gpsfake with the 5 Hz turn track
# (tests/data/gnss/turn_track.nmea, tools/gnss/make_turn_track.py: 16 m north, a 90-degree
# right turn on a 12 m circle, 16 m east) over a field of uniform weed density, twice:
#  1. [turn] compensation = true: on the turn the inner nozzle's volume per area (from its duty
#     by the calibrated line at the logged pressure, over the ground its logged patch positions
#     swept) equals the outer's within 5 %; and `sprayctl calibrate-wheel --distance 12` on the
#     first straight finds the simulated wheel's slip (100 x 1.05 pulses/m, at the simulation's
#     pace against the track's: within 3 %, and more than 3 % from the configured 100);
#  2. compensation = false: the same figure differs by the ratio of the nozzles' radii
#     (13.75 / 10.25 = 1.34), more than 20 %.
# usage: turn_sim_test.sh BUILD_DIR SOURCE_DIR
set -euo pipefail
BUILD=$(realpath "$1")
SOURCE=$(realpath "$2")
WEEDSPRAYD=$BUILD/daemon/weedsprayd
SPRAYCTL=$BUILD/daemon/sprayctl
PY=/usr/bin/python3
. "$(dirname "$0")/private_bus_lib.sh" turn
. "$(dirname "$0")/gpsfake_lib.sh"
FAIL_LOGS=("$T/true/daemon.log" "$T/true/gpsfake.log" "$T/false/daemon.log" "$T/false/gpsfake.log")
require_gpsfake

# A field of uniform weed density: an 8 px green/soil checkerboard (half of every zone green).
mkdir -p "$T/field"
$PY - "$T/field/checker.png" "$(dirname "$0")" <<'PYEOF'
import sys
sys.path.insert(0, sys.argv[2])
from png_file import write_png
write_png(sys.argv[1], 640, 400,
          lambda x, y: (0, 150, 0) if ((x // 8) + (y // 8)) % 2 == 0 else (100, 70, 50))
PYEOF

start_private_bus

# run COMPENSATION: one drive along the track; the as-applied log in $T/$1/log.
run() {
  local dir=$T/$1
  mkdir -p "$dir/state"
  local port
  port=$(free_port)
  cat >"$dir/weedspray.toml" <<TOML
[boom]
nozzles = 8
nozzle_width_m = 0.5
[spray]
nominal_flow_l_per_min = 0.8
nominal_speed_m_per_s = 2.0
calibration_slope_l_per_min_per_pct = 0.00393
calibration_offset_l_per_min = 0.217
calibration_pressure_mpa = 0.4
[gnss]
enabled = true
host = "127.0.0.1"
port = $port
first_fix_timeout_s = 30.0
reconnect_max_s = 0.25  # gpsfake gives up when no client watches within -W 2 s
[speed]
source = "gnss"
[turn]
compensation = $1
[sim]
speed_profile = "constant"
speed_max_m_per_s = 2.0
images_dir = "$T/field"
wheel_slip_pct = 5.0
TOML
  "$WEEDSPRAYD" --sim --user --config "$dir/weedspray.toml" --state-dir "$dir/state" \
    >"$dir/daemon.log" 2>&1 &
  DAEMON_PID=$!
  for _ in $(seq 1 100); do
    "$SPRAYCTL" --user status >/dev/null 2>&1 && break
    kill -0 "$DAEMON_PID" 2>/dev/null || fail "weedsprayd exited"
    sleep 0.1
  done
  "$SPRAYCTL" --user start || fail "sprayctl start"
  if [ "$1" = true ]; then
    "$SPRAYCTL" --user calibrate-wheel --distance 12 --timeout 40 >"$dir/calibration.txt" 2>&1 &
    CAL_PID=$!
  fi
  # The track in real time: 3 sentences an epoch, 0.2 s an epoch.
  start_gpsfake "$port" "$dir/gpsfake.log" -1 -q -c 0.0667 -W 2 \
    "$SOURCE/tests/data/gnss/turn_track.nmea"
  # Drive until the track's stop (15:00:25.4-15:00:28.4), then stop spraying and the daemon.
  local done=
  for _ in $(seq 1 600); do
    gnss_time=$("$SPRAYCTL" --user status --json 2>/dev/null |
      $PY -c 'import json,sys; print(json.load(sys.stdin)["GnssTime"])' 2>/dev/null || true)
    if [[ "$gnss_time" > "2026-06-25T15:00:28" ]]; then
      done=1
      break
    fi
    kill -0 "$DAEMON_PID" 2>/dev/null || fail "weedsprayd exited"
    sleep 0.1
  done
  [ -n "$done" ] || fail "the track's end never came ($1): $("$SPRAYCTL" --user status 2>&1 | grep -v Nozzle)"
  if [ "$1" = true ]; then
    wait "$CAL_PID" || fail "calibrate-wheel: $(cat "$dir/calibration.txt")"
  fi
  kill -TERM "$DAEMON_PID"
  wait "$DAEMON_PID" || fail "weedsprayd exit status $? ($1)"
  DAEMON_PID=
  stop_gpsfake
}

run true
run false

# Volume per area of nozzle 0 (left: the outer) and 7 (right: the inner) on the steady part of
# the turn (the track turns 15:00:08.0-15:00:17.4; the yaw rate settles within ~1.5 s).
$PY - "$T" <<'PYEOF' || fail "volume per area on the turn"
import csv, glob, math, sys
T = sys.argv[1]
A, B, P_CAL = 0.00393, 0.217, 0.4  # the test's calibrated line
W = 0.5

def ground(lat1, lon1, lat2, lon2):  # metres, local WGS84 radii (as control/wheel_calibration)
    a, e2 = 6378137.0, 6.69437999014e-3
    phi = math.radians((lat1 + lat2) / 2)
    w = 1 - e2 * math.sin(phi) ** 2
    m, n = a * (1 - e2) / w ** 1.5, a / math.sqrt(w)
    return math.hypot(math.radians(lat2 - lat1) * m, math.radians(lon2 - lon1) * n * math.cos(phi))

def per_area(run, nozzle):
    rows = []
    for path in sorted(glob.glob(f"{T}/{run}/state/as-applied/as-applied-*.csv")):
        with open(path) as f:
            rows += [r for r in csv.DictReader(f)]
    volume = area = 0.0
    prev = None
    for r in rows:
        inside = "2026-06-25T15:00:10" <= r["utc"] <= "2026-06-25T15:00:16.5"
        lat, lon = r.get(f"latitude_deg_{nozzle}"), r.get(f"longitude_deg_{nozzle}")
        if not inside or not lat:
            prev = None
            continue
        t, lat, lon = float(r["time_s"]), float(lat), float(lon)
        if prev is not None:
            duty = float(r[f"duty_pct_{nozzle}"])
            flow = 0.0 if duty <= 0 else (A * min(duty, 100) + B) * math.sqrt(
                max(float(r["pressure_mpa"]), 0) / P_CAL)
            volume += flow / 60.0 * (t - prev[0])
            area += ground(prev[1], prev[2], lat, lon) * W
        prev = (t, lat, lon)
    if area <= 0:
        sys.exit(f"{run}: no positioned records of nozzle {nozzle} on the turn")
    return volume / area * 10000.0, area

results = {}
for run in ("true", "false"):
    outer, outer_area = per_area(run, 0)
    inner, inner_area = per_area(run, 7)
    results[run] = inner / outer
    print(f"compensation={run}: outer {outer:.1f} L/ha over {outer_area:.2f} m2, inner "
          f"{inner:.1f} L/ha over {inner_area:.2f} m2, inner/outer {inner / outer:.3f}")
ok = abs(results["true"] - 1) <= 0.05 and results["false"] - 1 > 0.20
sys.exit(0 if ok else 1)
PYEOF

# The wheel: 100 pulses/m configured, the simulated wheel slips 5 %: 105 per metre of the
# simulation's ground. The simulation and gpsfake each keep their own pace (both a little slow
# of the wall clock, more so on a loaded machine), so the truth is what the as-applied log
# shows: the wheel's odometer (pulses / 100) against the track's time (the fix's UTC carried to
# each record), a least-squares line over the first straight (one record's UTC carries the
# jitter of its fix's arrival, up to a tenth of a second: two end points alone were 2-4 % off
# over 6 s), at the track's 2 m/s. Against it the calibration read -0.1 to +1.2 % (5 runs), the
# two clocks drifting apart at their own pace; the calibration's own precision is the unit
# tests' (0.1 % over a noisy 100 m). So this checks that the daemon's calibration finds the
# slip: within 3 % of the log's truth, and more than 3 % from the configured 100.
cat "$T/true/calibration.txt"
ppm=$(sed -n 's/^pulses_per_metre = //p' "$T/true/calibration.txt")
$PY - "$T/true/state/as-applied" "$ppm" <<'PYEOF' || fail "calibrate-wheel measured $ppm pulses/m"
import csv, datetime, glob, sys
points = []  # (track time s, odometer m) of each positioned record on the first straight
for path in sorted(glob.glob(sys.argv[1] + "/as-applied-*.csv")):
    for r in csv.DictReader(open(path)):
        if "2026-06-25T15:00:00.4" <= r["utc"] <= "2026-06-25T15:00:07.6":
            t = datetime.datetime.fromisoformat(r["utc"].replace("Z", "+00:00")).timestamp()
            points.append((t, float(r["distance_m"])))
if len(points) < 20:
    sys.exit(f"{len(points)} positioned records on the first straight")
n = len(points)
mt = sum(t for t, _ in points) / n
md = sum(d for _, d in points) / n
slope = sum((t - mt) * (d - md) for t, d in points) / sum((t - mt) ** 2 for t, _ in points)
truth = 100.0 * slope / 2.0  # wheel pulses per metre of the track
measured = float(sys.argv[2])
print(f"wheel: measured {measured:.2f} pulses/m, truth {truth:.2f} from the log ({n} records; "
      f"105 x the simulation's pace against the track's), error "
      f"{100 * (measured / truth - 1):+.2f} %; configured 100")
sys.exit(0 if abs(measured / truth - 1) <= 0.03 and abs(measured / 100.0 - 1) > 0.03 else 1)
PYEOF
echo "PASS"
