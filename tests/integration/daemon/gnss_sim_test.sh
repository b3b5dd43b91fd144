#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# weedsprayd --sim with [gnss] on a real gpsd fed the project's recorded track by gpsfake
# (tests/data/gnss, tools/gnss/make_track.py), speed.source = "gnss", on a PRIVATE session bus:
#  1. GnssFix 3d, Position on the track, SpeedSource gnss and the rate law's Speed the
#     receiver's (2 m/s; the simulated wheel turns at 1 m/s);
#  2. gpsfake stops: gnss_fix_lost is raised, GnssFix none, and the speed falls back to the
#     wheel's pulses (SpeedSource "wheel (gnss fix lost)", Speed 1 m/s); SIGTERM -> exit 0.
#  3. Maps: the daemon sprayed the track (Start after the first fix) with its antenna 2 m ahead
#     of the nozzles and 0.3 m right of the boom's centre; `sprayctl export-map` in each format
#     is read back with ogrinfo (both layers, feature count > 0, fields, CRS EPSG:4326) and,
#     converted to GeoJSON by ogr2ogr, checked by map_check.py against the log and the track.
# usage: gnss_sim_test.sh BUILD_DIR SOURCE_DIR
set -euo pipefail
BUILD=$(realpath "$1")
SOURCE=$(realpath "$2")
WEEDSPRAYD=$BUILD/daemon/weedsprayd
SPRAYCTL=$BUILD/daemon/sprayctl
PY=/usr/bin/python3
. "$(dirname "$0")/private_bus_lib.sh" gnss
. "$(dirname "$0")/gpsfake_lib.sh"
FAIL_LOGS+=("$T/gpsfake.log")
require_gpsfake
start_private_bus

status_json() { "$SPRAYCTL" --user status --json; }
# json_check EXPR: true when the python expression holds for the status object j.
json_check() {
  status_json | $PY -c "import json,sys; j=json.load(sys.stdin); sys.exit(0 if ($1) else 1)"
}
wait_for() {  # wait_for SECONDS EXPR
  local tries=$(($1 * 10))
  for _ in $(seq 1 "$tries"); do
    json_check "$2" 2>/dev/null && return 0
    kill -0 "$DAEMON_PID" 2>/dev/null || fail "weedsprayd exited"
    sleep 0.1
  done
  return 1
}

PORT=$(free_port)
mkdir -p "$T/state"
cat >"$T/weedspray.toml" <<TOML
[gnss]
enabled = true
host = "127.0.0.1"
port = $PORT
lost_fix_timeout_s = 2.0  # margin for a loaded machine (gpsfake paces in Python)
antenna_ahead_of_nozzles_m = 2.0
antenna_right_of_centre_m = 0.3
first_fix_timeout_s = 30.0  # gpsfake starts after the daemon (below)
reconnect_max_s = 0.25  # gpsfake gives up when no client watches within -W 2 s
[speed]
source = "gnss"
[sim]
speed_profile = "constant"
speed_max_m_per_s = 1.0
TOML
"$WEEDSPRAYD" --sim --user --config "$T/weedspray.toml" --state-dir "$T/state" \
  >"$T/daemon.log" 2>&1 &
DAEMON_PID=$!

# The track plays on gpsfake's clock (the turn 4-7 s in, its stop at 12 s): it starts only once
# the daemon answers on the bus, so a slow start-up on a loaded machine cannot miss the turn.
for _ in $(seq 1 300); do
  "$SPRAYCTL" --user status >/dev/null 2>&1 && break
  kill -0 "$DAEMON_PID" 2>/dev/null || fail "weedsprayd exited"
  sleep 0.1
done
"$SPRAYCTL" --user status >/dev/null 2>&1 || fail "weedsprayd never answered on the bus"
# The track once, 0.1 s a sentence (0.3 s an epoch, ~10 s in all); -W: gpsfake ends 2 s after.
start_gpsfake "$PORT" "$T/gpsfake.log" -1 -q -c 0.1 -W 2 "$SOURCE/tests/data/gnss/field_track.nmea"
$PY - "$PORT" <<'PYEOF' || fail "gpsd never listened on port $PORT"
import socket, sys, time
for _ in range(100):
    try:
        socket.create_connection(("127.0.0.1", int(sys.argv[1])), timeout=1).close()
        sys.exit(0)
    except OSError:
        time.sleep(0.1)
sys.exit(1)
PYEOF

# 1. The receiver's fix on the bus, and its speed in the rate law.
wait_for 15 'j["GnssFix"] == "3d" and j["SpeedSource"] == "gnss" and
  abs(j["GnssSpeed"] - 2.0) < 0.001 and j["Speed"] == j["GnssSpeed"]' ||
  fail "no 3d fix with Speed from gnss: $(status_json)"
json_check 'abs(j["Position"][0] - 52.0) < 0.001 and abs(j["Position"][1] - 5.0) < 0.001 and
  j["GnssTime"].startswith("2026-06-24T14:30:") and "gnss_fix_lost" not in j["Alarms"]' ||
  fail "Position/GNSS fields: $(status_json)"
echo "ok: 3d fix, Position on the track, Speed from gnss"
"$SPRAYCTL" --user start || fail "Start refused"
# The turn: the course swings between north and east; the sky view (GSV every 4 s) arrives.
wait_for 10 '5 < j["Course"] < 85' || fail "never saw the turn's course: $(status_json)"
# gpsd's first reports of a stream may lack the altitude (a TPV before the epoch's GGA).
wait_for 5 'j["GnssSatellites"] == 9 and abs(j["GnssHdop"] - 0.8) < 1e-9 and
  abs(j["Position"][2] - 12.5) < 1e-6' || fail "satellites, HDOP and altitude: $(status_json)"
json_check '"gnss_fix_lost" not in j["Alarms"]' || fail "gnss_fix_lost while the fix is good: $(status_json)"
echo "ok: the turn's course, 9 satellites, HDOP 0.8, altitude, no alarm"
"$SPRAYCTL" --user status | grep -q "^GNSS: *3d fix, position 52.0" || fail "sprayctl status: $("$SPRAYCTL" --user status)"

# 2. gpsd goes away: alarm, GnssFix none, speed from the wheel.
wait_for 8 'j["GnssTime"] >= "2026-06-24T14:30:27"' || fail "the track's stop never came"
stop_gpsfake
wait_for 5 '"gnss_fix_lost" in j["Alarms"] and j["GnssFix"] == "none" and
  j["SpeedSource"] == "wheel (gnss fix lost)" and abs(j["Speed"] - 1.0) < 0.1' ||
  fail "no fallback after gpsd stopped: $(status_json)"
grep -q "alarm raised: gnss_fix_lost (warning; no usable fix for 2 s; gpsd at 127.0.0.1:$PORT not reachable; speed from wheel)" \
  "$T/daemon.log" || fail "the alarm's log line"
echo "ok: gnss_fix_lost, speed from the wheel"

kill -TERM "$DAEMON_PID"
wait "$DAEMON_PID" || fail "weedsprayd exit status $?"
DAEMON_PID=

# 3. Maps from the as-applied log the run left.
LOG="$T/state/as-applied"
for format in gpkg shp geojson; do
  out="$T/map.$format"
  "$SPRAYCTL" export-map --format "$format" --dir "$LOG" "$out" >"$T/export.log" 2>&1 ||
    fail "export-map --format $format: $(cat "$T/export.log")"
  grep -q " [1-9][0-9]* sprayed polygons" "$T/export.log" || fail "export-map: $(cat "$T/export.log")"
  # GeoJSON holds one layer a file: OUT is a folder of them.
  src() { if [ "$format" = geojson ]; then echo "$out/$1.geojson"; else echo "$out"; fi; }
  for layer in sprayed weed_density; do
    info=$(ogrinfo -so "$(src $layer)" "$layer" 2>&1) || fail "ogrinfo $(src $layer) $layer: $info"
    grep -q "^Feature Count: [1-9]" <<<"$info" || fail "$format $layer: no features: $info"
    # The layer's CRS itself (a projected CRS's WKT names EPSG:4326 too, as its base).
    grep -q '^GEOGCRS\["WGS 84",$' <<<"$info" && grep -q '^    ID\["EPSG",4326\]\]$' <<<"$info" ||
      fail "$format $layer: CRS is not EPSG:4326: $info"
    grep -q "^Geometry: Polygon" <<<"$info" || fail "$format $layer: not polygons: $info"
  done
  info=$(ogrinfo -so "$(src sprayed)" sprayed)
  for field in nozzle utc_start utc_end rate_l_ha volume_l area_m2 duty_pct weed_dens crop_dens speed_m_s; do
    grep -q "^$field: " <<<"$info" || fail "$format sprayed: no field $field: $info"
  done
  mkdir -p "$T/json.$format"
  for layer in sprayed weed_density; do
    ogr2ogr -f GeoJSON "$T/json.$format/$layer.geojson" "$(src $layer)" "$layer" ||
      fail "ogr2ogr $out $layer"
  done
  $PY "$SOURCE/tests/integration/daemon/map_check.py" "$T/json.$format/sprayed.geojson" \
    "$T/json.$format/weed_density.geojson" "$LOG" "$SOURCE/tests/data/gnss/field_track.nmea" \
    2.0 0.3 || fail "map_check on the $format export"
done
# A UTC window: fewer stretches, each inside it.
"$SPRAYCTL" export-map --format geojson --dir "$LOG" --from 2026-06-24T14:30:08Z \
  --to 2026-06-24T14:30:20.5Z "$T/window" >/dev/null || fail "export-map --from/--to"
$PY - "$T/window/sprayed.geojson" "$T/json.geojson/sprayed.geojson" <<'PYEOF' || fail "the --from/--to window"
import json, sys
part = [f["properties"] for f in json.load(open(sys.argv[1]))["features"]]
whole = json.load(open(sys.argv[2]))["features"]
assert 0 < len(part) < len(whole), (len(part), len(whole))
# Records are picked by their UTC; a stretch's first one covers the record period before it.
for p in part:
    assert "2026-06-24T14:30:07.800Z" <= p["utc_start"], p
    assert "2026-06-24T14:30:08.000Z" <= p["utc_end"] <= "2026-06-24T14:30:20.500Z", p
PYEOF
# An existing OUT is kept unless --overwrite; a bad --from names itself.
"$SPRAYCTL" export-map --format gpkg --dir "$LOG" "$T/map.gpkg" 2>"$T/err.txt" &&
  fail "export-map replaced an existing file without --overwrite"
grep -q "map.gpkg: exists" "$T/err.txt" || fail "existing OUT: $(cat "$T/err.txt")"
"$SPRAYCTL" export-map --format gpkg --dir "$LOG" --from 2026-06-24T25:00 "$T/x.gpkg" 2>"$T/err.txt" &&
  fail "export-map accepted --from 2026-06-24T25:00"
grep -q -- "--from 2026-06-24T25:00: not a UTC time" "$T/err.txt" || fail "bad --from: $(cat "$T/err.txt")"
echo "ok: export-map gpkg, shp, geojson read back by ogrinfo and map_check.py"
echo "PASS"
