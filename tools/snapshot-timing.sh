#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Live-view figures: runs `weedsprayd --sim` on a private session bus, its camera replaying a
# synthetic WxH field (soil with green blocks), spraying, and takes N snapshots 0.6 s apart
# with `sprayctl snapshot`. Prints mean/sd/worst of: the call's wall time (waiting for the
# camera's next frame + overlay + PNG + transfer), the daemon's overlay+PNG time on its
# encoder thread (its debug log line), and the PNG size; --json: one JSON object instead.
#   tools/snapshot-timing.sh [--count N] [--size WxH] [--build DIR] [--json]
set -euo pipefail
cd "$(dirname "$0")/.."
count=20 size=1280x800 build=build/default json=0
while (($#)); do
  case "$1" in
    --count) count="$2"; shift ;;
    --size) size="$2"; shift ;;
    --build) build="$2"; shift ;;
    --json) json=1 ;;
    *) sed -n '2,7p' "$0"; exit 2 ;;
  esac
  shift
done
tmp=$(mktemp -d)
trap 'kill $(jobs -p) 2>/dev/null || true; [ -n "${bus:-}" ] && kill "$bus" 2>/dev/null; rm -rf "$tmp"' EXIT
mkdir -p "$tmp/images"
/usr/bin/python3 - "$tmp/images/field.png" "${size%x*}" "${size#*x}" <<'PYEOF'
import sys, cv2, numpy as np
w, h = int(sys.argv[2]), int(sys.argv[3])
rng = np.random.default_rng(1)
img = np.zeros((h, w, 3), np.uint8)
img[:] = (70, 100, 130)
for _ in range(40):  # plants of all sizes: a PNG that compresses like a field's overlay
    x, y, r = rng.integers(0, w), rng.integers(0, h), rng.integers(4, max(5, w // 30))
    cv2.circle(img, (int(x), int(y)), int(r), (40, 150, 60), -1)
img = cv2.add(img, rng.integers(0, 12, img.shape, dtype=np.uint8))  # sensor noise
assert cv2.imwrite(sys.argv[1], img)
PYEOF
printf '[daemon]\nlog_level = "debug"\nautostart = true\n[sim]\nspeed_profile = "constant"\nspeed_max_m_per_s = 2.0\n' \
  >"$tmp/weedspray.toml"
dbus-daemon --session --fork --nopidfile --print-address=3 --print-pid=4 3>"$tmp/bus.addr" 4>"$tmp/bus.pid"
export DBUS_SESSION_BUS_ADDRESS=$(cat "$tmp/bus.addr")
bus=$(cat "$tmp/bus.pid")
"$build/daemon/weedsprayd" --sim --user --config "$tmp/weedspray.toml" --state-dir "$tmp/state" \
  --sim-images "$tmp/images" >"$tmp/daemon.log" 2>&1 &
for _ in $(seq 1 50); do
  "$build/daemon/sprayctl" --user snapshot "$tmp/warm.png" >/dev/null 2>&1 && break
  sleep 0.3
done
: >"$tmp/calls.txt"
for i in $(seq 1 "$count"); do
  sleep 0.6
  start=$(date +%s%N)
  "$build/daemon/sprayctl" --user snapshot "$tmp/s$i.png" >/dev/null
  echo "$(( ($(date +%s%N) - start) / 1000 )) $(stat -c %s "$tmp/s$i.png")" >>"$tmp/calls.txt"
done
/usr/bin/python3 - "$tmp/calls.txt" "$tmp/daemon.log" "$size" "$json" <<'PYEOF'
import json, re, statistics as st, sys
calls = [tuple(map(int, l.split())) for l in open(sys.argv[1])]
encode = [float(m.group(1)) for m in re.finditer(r"overlay \+ PNG ([0-9.]+) ms", open(sys.argv[2]).read())][1:]
if sys.argv[4] == "1":
    stats = lambda xs: {"mean": round(st.mean(xs), 2), "sd": round(st.pstdev(xs), 2), "worst": round(max(xs), 2), "n": len(xs)}
    print(json.dumps({"frame": sys.argv[3], "snapshot_call_ms": stats([c[0] / 1000 for c in calls]),
                      "overlay_png_ms": stats(encode), "png_kib": stats([c[1] / 1024 for c in calls])}))
    sys.exit(0)
def show(name, xs, unit):
    print(f"{name:28s} mean {st.mean(xs):8.1f}  sd {st.pstdev(xs):7.1f}  worst {max(xs):8.1f} {unit}  (n={len(xs)})")
print(f"live view, {sys.argv[3]} frame, sim camera at 2 m/s:")
show("sprayctl snapshot wall time", [c[0] / 1000 for c in calls], "ms")
show("overlay + PNG (encoder)", encode, "ms")
show("PNG size", [c[1] / 1024 for c in calls], "KiB")
PYEOF
