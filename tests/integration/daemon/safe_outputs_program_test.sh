#!/usr/bin/env bash
# weedspray-safe-outputs, the unit's ExecStopPost: it loads none of OpenCV (so it starts in
# milliseconds), it still writes the outputs when the weed model is missing or broken (a vision
# problem must never keep the valves open), and its errors name the file, line and key, or the
# output and device it could not write. (Its writes to real lines are checked in the systemd
# guest, tests/vm-systemd: valves and pump low after stop, kill -9 and crashes.)
set -euo pipefail
BUILD=$1
BIN="$BUILD/daemon/weedspray-safe-outputs"
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
fail() { echo "FAIL: $*"; cat "$T"/*.log 2>/dev/null; exit 1; }

libs=$(ldd "$BIN")
if grep -q -i "opencv" <<<"$libs"; then fail "links OpenCV: $libs"; fi

# A configuration error names file, line and key; exit status 1.
printf '[gpio]\nchip = "gpiochip0"\nvalve_ofsets = [1, 2]\n' >"$T/typo.toml"
if "$BIN" --config "$T/typo.toml" >"$T/typo.log" 2>&1; then fail "a typo was accepted"; fi
grep -q "typo.toml:3.*gpio.valve_ofsets.*unknown key" "$T/typo.log" || fail "typo not located"

# A missing weed model: weedsprayd refuses the file, the safe writer goes on to the outputs.
cat >"$T/weedspray.toml" <<TOML
[vision]
weed_source = "dnn"
model = "$T/missing.onnx"
[gpio]
chip = "$T/no-such-gpiochip"
valve_offsets = [0, 1, 2, 3]
pump_offset = 4
TOML
if "$BUILD/daemon/weedsprayd" --check-config --config "$T/weedspray.toml" >"$T/check.log" 2>&1; then
  fail "weedsprayd accepted a missing model"
fi
grep -q "vision.model" "$T/check.log" || fail "weedsprayd did not name vision.model"
if "$BIN" --config "$T/weedspray.toml" >"$T/safe.log" 2>&1; then
  fail "no chip, yet the outputs were reported safe"
fi
grep -q "vision" "$T/safe.log" && fail "the safe writer stopped at the vision keys"
grep -q "^weedspray-safe-outputs: valves: .*no-such-gpiochip" "$T/safe.log" ||
  fail "the valves' error does not name the chip"
grep -q "^weedspray-safe-outputs: pump: " "$T/safe.log" || fail "the pump was not tried on its own"
# weedsprayd --safe-outputs is the same writer.
if "$BUILD/daemon/weedsprayd" --safe-outputs --config "$T/weedspray.toml" >"$T/daemon.log" 2>&1; then
  fail "weedsprayd --safe-outputs reported safe"
fi
grep -q "^weedsprayd --safe-outputs: valves: " "$T/daemon.log" || fail "weedsprayd --safe-outputs"
# --when-closed (the exit watcher weedsprayd starts): it waits while the pipe's write end lives,
# outlives SIGTERM (a stop signals the whole service), and writes as soon as that end closes,
# here when its holder is killed with SIGKILL. A missing chip is not retried.
mkfifo "$T/pipe"
sleep 600 >"$T/pipe" &
holder=$!
"$BIN" --config "$T/weedspray.toml" --when-closed 3 3<"$T/pipe" >"$T/watch.log" 2>&1 &
watcher=$!
sleep 0.5
kill -TERM "$watcher"
sleep 0.3
kill -0 "$watcher" 2>/dev/null || fail "the watcher did not outlive SIGTERM"
[ -s "$T/watch.log" ] && fail "the watcher wrote before its holder ended"
start=$(date +%s%N)
kill -KILL "$holder"
wait "$watcher" && fail "no chip, yet the watcher reported safe"
elapsed_ms=$((($(date +%s%N) - start) / 1000000))
grep -q "^weedspray-safe-outputs: valves: .*no-such-gpiochip" "$T/watch.log" ||
  fail "the watcher did not try the valves after its holder ended"
[ "$elapsed_ms" -lt 1000 ] || fail "the watcher took $elapsed_ms ms (a missing chip is not retried)"
echo "PASS"
