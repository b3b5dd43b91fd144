#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The simulated sprayer on a simulated field in WGS84: a real gpsd fed by gpsfake plays the
# project's 5 Hz turn track (tests/data/gnss/turn_track.nmea: 16 m north, a 90-degree right turn
# on a 12 m circle, 16 m east, a stop at the headland) over and over in real time, and
# weedsprayd --sim takes its speed, course (turn compensation) and positions (the as-applied
# log's map columns, `sprayctl export-map`) from it. `./dev sim --field` runs this.
#   tools/gnss/sim-field.sh [weedsprayd options...]
set -euo pipefail
here=$(cd "$(dirname "$0")/../.." && pwd)
[ -x /usr/bin/gpsfake ] && [ -x /usr/sbin/gpsd ] ||
  { echo "sim-field: gpsd and gpsfake are needed (./dev deps installs them)" >&2; exit 1; }
work=$(mktemp -d /tmp/weedspray-sim-field.XXXXXX)
port=$(python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
# gpsfake and its gpsd in a process group of their own, gone with this script.
setsid /usr/bin/gpsfake -q -c 0.0667 -P "$port" "$here/tests/data/gnss/turn_track.nmea" \
  >"$work/gpsfake.log" 2>&1 &
gpsfake_pid=$!
trap 'kill -TERM -- "-$gpsfake_pid" 2>/dev/null || true; rm -rf "$work"' EXIT
cat >"$work/weedspray.toml" <<TOML
# written by tools/gnss/sim-field.sh: the defaults, plus GNSS from the simulated field
[gnss]
enabled = true
host = "127.0.0.1"
port = $port
reconnect_max_s = 0.25  # gpsfake stops feeding when no client watches for 60 s
[speed]
source = "gnss"
[sim]
speed_profile = "constant"
speed_max_m_per_s = 2.0  # the track's speed
TOML
echo "sim-field: gpsd on 127.0.0.1:$port plays tests/data/gnss/turn_track.nmea in a loop"
"$here/tools/with-session-bus.sh" "$here/build/default/daemon/weedsprayd" --sim --user \
  --config "$work/weedspray.toml" "$@"
