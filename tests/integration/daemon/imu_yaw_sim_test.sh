#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Turn compensation from an IIO gyro: weedsprayd --sim (8 nozzles, 4 m boom, 2 m/s, no GNSS) with
# turn.yaw_source = "imu" on a fake IIO sysfs tree shaped as inv_mpu6050 shows an MPU-6050:
#  1. the gyro's z axis reads a right turn at 9.55 deg/s (2 m/s on a 12 m radius): YawRate
#     equals it, and the left (outer) nozzle's duty is above the right (inner) nozzle's;
#  2. the gyro reads 0: YawRate 0 and the end nozzles' duties equal;
#  3. the gyro's file turns unreadable: the rate goes stale and YawRate returns to 0.
# usage: imu_yaw_sim_test.sh BUILD_DIR
set -euo pipefail
BUILD=$(realpath "$1")
WEEDSPRAYD=$BUILD/daemon/weedsprayd
SPRAYCTL=$BUILD/daemon/sprayctl
PY=/usr/bin/python3
. "$(dirname "$0")/private_bus_lib.sh" imu
start_private_bus

IMU=$T/iio/iio:device0
mkdir -p "$IMU" "$T/state"
echo mpu6050 >"$IMU/name"
echo 0.000133090 >"$IMU/in_anglvel_scale"  # rad/s per count (250 deg/s range)
# 9.549 deg/s clockwise about an up z axis: -(9.549 pi / 180) / 0.000133090 counts
echo -1252 >"$IMU/in_anglvel_z_raw"
cat >"$T/weedspray.toml" <<TOML
[boom]
nozzles = 8
[spray]
nominal_flow_l_per_min = 0.8
nominal_speed_m_per_s = 2.0
[turn]
yaw_source = "imu"
imu_device = "$IMU"
[sim]
speed_profile = "constant"
speed_max_m_per_s = 2.0
TOML
"$WEEDSPRAYD" --sim --user --config "$T/weedspray.toml" --state-dir "$T/state" >"$T/daemon.log" 2>&1 &
DAEMON_PID=$!
json_check() {
  "$SPRAYCTL" --user status --json 2>/dev/null |
    $PY -c "import json,sys; j=json.load(sys.stdin); d=j['NozzleDuty']; sys.exit(0 if ($1) else 1)"  2>/dev/null
}
wait_for() {  # wait_for SECONDS EXPR
  for _ in $(seq 1 $(($1 * 10))); do
    json_check "$2" && return 0
    kill -0 "$DAEMON_PID" 2>/dev/null || fail "weedsprayd exited"
    sleep 0.1
  done
  return 1
}
wait_for 10 'j["State"] in ("Idle", "Spraying")' || fail "no sprayer on the bus"
"$SPRAYCTL" --user start
wait_for 10 'abs(j["YawRate"] - 9.549) < 0.01' || fail "YawRate from the gyro: $("$SPRAYCTL" --user status)"
wait_for 10 'd[0] > 0 and d[7] > 0 and d[0] > d[7] + 5' ||
  fail "outer (left) duty not above inner (right): $("$SPRAYCTL" --user status)"
echo "ok: YawRate 9.549 deg/s from the gyro; outer duty above inner"
echo 0 >"$IMU/in_anglvel_z_raw"
wait_for 10 'j["YawRate"] == 0 and d[0] == d[7] and d[0] > 0' ||
  fail "straight: $("$SPRAYCTL" --user status)"
echo "ok: straight: YawRate 0, end duties equal"
echo -1252 >"$IMU/in_anglvel_z_raw"
wait_for 10 'abs(j["YawRate"] - 9.549) < 0.01' || fail "the turn again"
echo garbage >"$IMU/in_anglvel_z_raw"
wait_for 10 'j["YawRate"] == 0' || fail "a gyro that cannot be read still steers: $("$SPRAYCTL" --user status)"
echo "ok: unreadable gyro: the rate goes stale, YawRate 0"
kill -TERM "$DAEMON_PID"
wait "$DAEMON_PID" || fail "weedsprayd exit status $?"
DAEMON_PID=
echo PASS
