# SPDX-License-Identifier: Apache-2.0
# shellcheck shell=bash
# Sourced (after private_bus_lib.sh) by the daemon's GNSS test scripts: a real gpsd fed an NMEA
# track by gpsfake, on a free port, in a process group of its own (gpsd goes with it), stopped
# at exit.
#   require_gpsfake; PORT=$(free_port); start_gpsfake PORT LOG ARGS... TRACK; stop_gpsfake
GPSFAKE_PID=

require_gpsfake() {
  [ -x /usr/bin/gpsfake ] && [ -x /usr/sbin/gpsd ] ||
    fail "gpsd and gpsfake are required (apt-get install gpsd gpsd-clients; ./dev deps installs them)"
}

# A free port BELOW the kernel's ephemeral range (net.ipv4.ip_local_port_range): the daemon
# dials gpsd's port every fraction of a second until gpsfake's gpsd listens, and a connect()
# to a port inside the range can be given that very port as its own local one (TCP's
# simultaneous open: the socket connects to itself and reads back its own WATCH, never a
# fix). Outside the range no local port can equal it.
free_port() {
  /usr/bin/python3 -c '
import random, socket
low = int(open("/proc/sys/net/ipv4/ip_local_port_range").read().split()[0])
for _ in range(200):
    port = random.randrange(10000, low)
    s = socket.socket()
    try:
        s.bind(("127.0.0.1", port))
    except OSError:
        continue
    finally:
        s.close()
    print(port)
    break
else:
    raise SystemExit("no free port below the ephemeral range")
'
}

start_gpsfake() {  # start_gpsfake PORT LOG [gpsfake options...] TRACK
  local port=$1 log=$2
  shift 2
  setsid /usr/bin/gpsfake -P "$port" "$@" >"$log" 2>&1 &
  GPSFAKE_PID=$!
}

stop_gpsfake() {
  [ -n "$GPSFAKE_PID" ] && kill -TERM -- "-$GPSFAKE_PID" 2>/dev/null || true
  sleep 0.3
  [ -n "$GPSFAKE_PID" ] && kill -KILL -- "-$GPSFAKE_PID" 2>/dev/null || true
  GPSFAKE_PID=
}
EXIT_HOOKS+=(stop_gpsfake)
