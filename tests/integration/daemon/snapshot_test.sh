#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The live view end to end: weedsprayd --sim on a PRIVATE session bus, its camera replaying a
# synthetic 320x200 field (soil, one green block); `sprayctl snapshot OUT.png` writes the PNG,
# which is decoded here (size = the camera's frame, weed red on the block, zone grid yellow,
# soil dimmed); a second call within the rate limit is refused with a clear error and writes
# nothing; a bad camera index is refused; after the limit's half second a call succeeds again.
# usage: snapshot_test.sh BUILD_DIR
set -euo pipefail
BUILD=$(realpath "$1")
WEEDSPRAYD=$BUILD/daemon/weedsprayd
SPRAYCTL=$BUILD/daemon/sprayctl
PY=/usr/bin/python3
. "$(dirname "$0")/private_bus_lib.sh" snapshot

# The field: brown soil with a green block over zone 2 (of 4 across), below the zone's text.
mkdir -p "$T/images" "$T/state"
# (A 24-bit BMP from plain Python: importing OpenCV twice costs seconds on a loaded machine.)
$PY - "$T/images/field.png" "$(dirname "$0")" <<'PYEOF'
import sys
sys.path.insert(0, sys.argv[2])
from png_file import write_png
# Soil, and one green block at x 170..229, y 110..189.
write_png(sys.argv[1], 320, 200, lambda x, y: (60, 150, 40) if 110 <= y < 190 and 170 <= x < 230
          else (130, 100, 70))
PYEOF
cat >"$T/weedspray.toml" <<'TOML'
[sim]
speed_profile = "constant"   # frames come as the vehicle moves: keep it moving
speed_max_m_per_s = 2.5     # the sim camera's frame rate follows the speed
TOML

start_private_bus

"$WEEDSPRAYD" --sim --user --config "$T/weedspray.toml" --state-dir "$T/state" \
  --sim-images "$T/images" --run-seconds 60 >"$T/daemon.log" 2>&1 &
DAEMON_PID=$!

# The first snapshot once the camera has delivered a frame (start-up takes a second or two).
got=0
for _ in $(seq 1 40); do
  kill -0 "$DAEMON_PID" 2>/dev/null || fail "weedsprayd exited"
  if "$SPRAYCTL" --user snapshot "$T/first.png" >"$T/out.txt" 2>"$T/err.txt"; then
    got=1
    break
  fi
  grep -q "no frame yet\|is not running" "$T/err.txt" ||
    fail "snapshot: $(cat "$T/err.txt")"
  sleep 0.25
done
[ "$got" = 1 ] || fail "no snapshot within 10 s: $(cat "$T/err.txt")"
grep -q "first.png: [0-9]* bytes (camera 0)" "$T/out.txt" || fail "sprayctl said: $(cat "$T/out.txt")"

# Within the rate limit (2 a second): refused, named, and nothing written. A second call that
# reached the daemon only after the half second (a machine too loaded to start sprayctl in
# time) proves nothing either way: then the pair is tried again.
refused=0
for _ in 1 2 3; do
  sleep 0.6
  "$SPRAYCTL" --user snapshot "$T/first.png" >/dev/null 2>"$T/err.txt" ||
    fail "snapshot: $(cat "$T/err.txt")"
  done_at=$(date +%s%N)
  if ! "$SPRAYCTL" --user snapshot "$T/second.png" 2>"$T/err.txt"; then
    refused=1
    break
  fi
  [ $(($(date +%s%N) - done_at)) -gt 400000000 ] || fail "a second snapshot at once was accepted"
  rm -f "$T/second.png"
done
[ "$refused" = 1 ] || fail "never refused (sprayctl always started late?)"
grep -q "org.weedspray.Sprayer1.Error.RateLimited: Snapshot refused: at most 2 a second" \
  "$T/err.txt" || fail "second snapshot: $(cat "$T/err.txt")"
[ ! -e "$T/second.png" ] || fail "a refused snapshot wrote a file"
echo "ok: a second snapshot within 0.5 s refused: $(cat "$T/err.txt")"

# Two at once: one waits for its frame, the other is refused (one at a time).
sleep 0.6
"$SPRAYCTL" --user snapshot "$T/a.png" >/dev/null 2>"$T/err_a.txt" &
A_PID=$!
"$SPRAYCTL" --user snapshot "$T/b.png" >/dev/null 2>"$T/err_b.txt" &
B_PID=$!
a=0 b=0
wait "$A_PID" || a=1
wait "$B_PID" || b=1
[ $((a + b)) = 1 ] || fail "two concurrent snapshots: failures $a $b, expected exactly one"
cat "$T/err_a.txt" "$T/err_b.txt" | grep -q "RateLimited: Snapshot refused" ||
  fail "concurrent refusal: $(cat "$T/err_a.txt" "$T/err_b.txt")"
echo "ok: of two concurrent snapshots one is answered, one refused"

if "$SPRAYCTL" --user snapshot --camera 3 "$T/bad.png" 2>"$T/err.txt"; then
  fail "camera 3 accepted (one camera configured)"
fi
grep -q "InvalidArgument: Snapshot: no camera 3 (1 configured)" "$T/err.txt" ||
  fail "camera 3: $(cat "$T/err.txt")"

# Decoded by a plain-Python PNG reader (not the OpenCV that wrote it, and no seconds-long
# import of it on a loaded machine).
$PY - "$T/first.png" <<'PYEOF' || fail "the PNG does not show the overlay"
import struct, sys, zlib
data = open(sys.argv[1], "rb").read()
assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
pos, idat = 8, b""
while pos < len(data):
    length, kind = struct.unpack(">I4s", data[pos:pos + 8])
    body = data[pos + 8:pos + 8 + length]
    if kind == b"IHDR":
        w, h, depth, colour = struct.unpack(">IIBB", body[:10])
    elif kind == b"IDAT":
        idat += body
    pos += 12 + length
assert (w, h) == (320, 200), f"size {w}x{h}, camera frames are 320x200"
assert (depth, colour) == (8, 2), f"bit depth {depth}, colour type {colour}: not 8-bit RGB"
raw, stride, rows, prev = zlib.decompress(idat), w * 3, [], bytearray(w * 3)
for y in range(h):
    f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
    for i in range(stride):
        a, b, c = line[i - 3] if i >= 3 else 0, prev[i], prev[i - 3] if i >= 3 else 0
        if f == 1: line[i] = (line[i] + a) & 255
        elif f == 2: line[i] = (line[i] + b) & 255
        elif f == 3: line[i] = (line[i] + (a + b) // 2) & 255
        elif f == 4:
            p = a + b - c
            pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
            line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
    rows.append(line)
    prev = line
px = lambda x, y: tuple(rows[y][3 * x:3 * x + 3])  # R G B
WEED, GRID = (255, 0, 0), (255, 255, 0)  # red, yellow
weed = sum(px(x, y) == WEED for y in range(h) for x in range(w))
block = sum(px(x, y) == WEED for y in range(115, 185) for x in range(175, 225))
assert block >= 0.95 * 70 * 50, f"only {block} of the green block's 3500 inner pixels are weed red"
assert weed <= 60 * 80, f"{weed} red pixels: more than the block"
# Grid: the zone borders at x = 0, 80, 160, 240 (4 zones over 320 px), full height.
for x in (0, 80, 160, 240, 319):
    assert sum(px(x, y) == GRID for y in range(h)) > h // 2, f"no grid line at x={x}"
assert px(120, 100) != GRID
# Soil is the frame dimmed to 60 % (PNG is lossless): B G R 70,100,130 -> R G B 78,60,42.
assert px(40, 180) == (78, 60, 42), px(40, 180)
# The densities and duties are written in: light (anti-aliased white) text in the zones' top
# rows, where the dimmed soil is dark; none lower down.
light = lambda y0, y1: sum(min(px(x, y)) >= 200 for y in range(y0, y1) for x in range(w))
assert light(0, 40) > 100, f"no text: {light(0, 40)} light pixels"
assert light(60, h) == 0, "light pixels outside the text rows"
print(f"ok: PNG 320x200, {weed} weed pixels on the block, grid at the zone borders")
PYEOF

sleep 0.6
"$SPRAYCTL" --user snapshot "$T/third.png" >/dev/null 2>"$T/err.txt" ||
  fail "a snapshot after the limit's interval refused: $(cat "$T/err.txt")"
[ -s "$T/third.png" ] || fail "third snapshot empty"
echo "ok: accepted again after 0.6 s"

kill -TERM "$DAEMON_PID"
rc=0
wait "$DAEMON_PID" || rc=$?
DAEMON_PID=
[ "$rc" -eq 0 ] || fail "exit status $rc"
echo "PASS"
