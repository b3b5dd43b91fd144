#!/usr/bin/env bash
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
$PY - "$T/images/field.png" <<'PYEOF'
import sys, cv2, numpy as np
img = np.zeros((200, 320, 3), np.uint8)
img[:] = (70, 100, 130)           # soil, B G R
img[110:190, 170:230] = (40, 150, 60)  # plants
assert cv2.imwrite(sys.argv[1], img)
PYEOF
cat >"$T/weedspray.toml" <<'TOML'
[sim]
speed_profile = "constant"   # frames come as the vehicle moves: keep it moving
speed_max_m_per_s = 1.0
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
  grep -q "no frame yet\|ServiceUnknown\|was not provided" "$T/err.txt" ||
    fail "snapshot: $(cat "$T/err.txt")"
  sleep 0.25
done
[ "$got" = 1 ] || fail "no snapshot within 10 s: $(cat "$T/err.txt")"
grep -q "first.png: [0-9]* bytes (camera 0)" "$T/out.txt" || fail "sprayctl said: $(cat "$T/out.txt")"

# Within the rate limit (2 a second): refused, named, and nothing written.
if "$SPRAYCTL" --user snapshot "$T/second.png" 2>"$T/err.txt"; then
  fail "a second snapshot at once was accepted"
fi
grep -q "org.weedspray.Sprayer1.Error.RateLimited: Snapshot refused: at most 2 a second" \
  "$T/err.txt" || fail "second snapshot: $(cat "$T/err.txt")"
[ ! -e "$T/second.png" ] || fail "a refused snapshot wrote a file"
echo "ok: a second snapshot within 0.5 s refused: $(cat "$T/err.txt")"

if "$SPRAYCTL" --user snapshot --camera 3 "$T/bad.png" 2>"$T/err.txt"; then
  fail "camera 3 accepted (one camera configured)"
fi
grep -q "InvalidArgument: Snapshot: no camera 3 (1 configured)" "$T/err.txt" ||
  fail "camera 3: $(cat "$T/err.txt")"

$PY - "$T/first.png" <<'PYEOF' || fail "the PNG does not show the overlay"
import sys, cv2, numpy as np
img = cv2.imread(sys.argv[1], cv2.IMREAD_UNCHANGED)
assert img is not None, "not a PNG OpenCV decodes"
assert img.shape == (200, 320, 3), f"size {img.shape}, camera frames are 320x200 BGR"
weed = np.all(img == (0, 0, 255), axis=2)
grid = np.all(img == (0, 255, 255), axis=2)
block = weed[115:185, 175:225]
assert block.mean() > 0.95, f"only {block.mean():.0%} of the green block is weed red"
assert weed.sum() <= 60 * 80, f"{weed.sum()} red pixels: more than the block"
# Grid: the zone borders at x = 0, 80, 160, 240 (4 zones over 320 px), full height.
for x in (0, 80, 160, 240, 319):
    assert grid[:, x].mean() > 0.5, f"no grid line at x={x}"
assert grid[100, 120] == False
# Soil is the frame dimmed to 60 % (PNG is lossless): 70,100,130 -> 42,60,78.
assert tuple(img[180, 40]) == (42, 60, 78), tuple(img[180, 40])
# The densities and duties are written in: light (anti-aliased white) text in the zones' top
# rows, where the dimmed soil is dark; none lower down.
light = np.all(img >= 200, axis=2)
assert light[:40].sum() > 100, f"no text: {light[:40].sum()} light pixels"
assert light[60:].sum() == 0, "light pixels outside the text rows"
print(f"ok: PNG 320x200, {weed.sum()} weed pixels on the block, grid at the zone borders")
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
