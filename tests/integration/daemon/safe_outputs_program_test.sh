#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# weedspray-safe-outputs, the unit's ExecStopPost: it loads none of OpenCV (so it starts in
# milliseconds), it still writes the outputs when the weed model is missing or broken (a vision
# problem must never keep the valves open), and its errors name the file, line and key, or the
# output and device it could not write. It reads the daemon's output manifest before the
# editable file, and writes each output on its own. (Its writes to real lines are checked in the systemd
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
# The return valve is written on its own: a missing pressure ADC does not stop the relief path
# opening (the DAC's raw value at full scale: 3.3 V / 1 mV = 3300 counts).
mkdir -p "$T/dac"
echo 1 >"$T/dac/out_voltage_scale"
echo 0 >"$T/dac/out_voltage0_raw"
cat >"$T/converters.toml" <<TOML
[gpio]
chip = "$T/no-such-gpiochip"
valve_offsets = [0, 1, 2, 3]
[adc]
iio_device = "$T/no-such-adc"
[dac]
iio_device = "$T/dac"
TOML
"$BIN" --config "$T/converters.toml" >"$T/converters.log" 2>&1 && fail "no chip, yet safe"
grep -q "return valve" "$T/converters.log" && fail "the return valve was not written on its own"
[ "$(cat "$T/dac/out_voltage0_raw")" = 3300 ] ||
  fail "return-valve DAC at $(cat "$T/dac/out_voltage0_raw") counts, not 3300 (fully open)"

# A reverse-acting return valve (open at 0 V): its safe write is 0 counts.
printf '[dac]\niio_device = "%s"\nreturn_valve_open_at = "zero"\n' "$T/dac" >"$T/reverse.toml"
: >"$T/dac/out_voltage0_raw" # a sysfs attribute takes each write whole; a file keeps the rest
"$BIN" --config "$T/reverse.toml" >"$T/reverse.log" 2>&1
[ "$(cat "$T/dac/out_voltage0_raw")" = 0 ] ||
  fail "reverse-acting return valve at $(cat "$T/dac/out_voltage0_raw") counts, not 0 (open)"

# The output manifest: weedsprayd writes the configuration it resolved at its start (here it
# then stops, finding no GPIO chip); a typo made in the file afterwards does not stop the safe
# writer, which reads the manifest and still tries the outputs the daemon drove.
cp "$T/converters.toml" "$T/machine.toml"
sed -i 's/^valve_offsets = .*/valve_offsets = [5, 6, 7, 8]\nheartbeat_opt_out = true\nestop_opt_out = true/' \
  "$T/machine.toml"
mkdir -p "$T/run"
if "$BUILD/daemon/weedsprayd" --no-bus --config "$T/machine.toml" \
  --output-manifest "$T/run/outputs.toml" --state-dir "$T/state" >"$T/start.log" 2>&1; then
  fail "weedsprayd started without a GPIO chip"
fi
grep -q "^valve_offsets = \[ 5, 6, 7, 8 \]" "$T/run/outputs.toml" ||
  fail "the manifest lacks the valves: $(grep -n valve "$T/run/outputs.toml")"
printf '[pump]\nofset = 3\n' >>"$T/machine.toml"
echo 0 >"$T/dac/out_voltage0_raw"
"$BIN" --config "$T/machine.toml" --manifest "$T/run/outputs.toml" >"$T/manifest.log" 2>&1 &&
  fail "no chip, yet safe"
grep -q "unknown\|ofset" "$T/manifest.log" && fail "the safe writer read the edited file"
grep -q "^weedspray-safe-outputs: valves: .*no-such-gpiochip" "$T/manifest.log" ||
  fail "the safe writer did not try the manifest's valves"
[ "$(cat "$T/dac/out_voltage0_raw")" = 3300 ] || fail "the manifest's return valve not written"
# Without a manifest (the daemon never started) the file is read, and its error named.
"$BIN" --config "$T/machine.toml" --manifest "$T/run/none.toml" >"$T/nomanifest.log" 2>&1 &&
  fail "a broken file, yet safe"
grep -q "no output manifest .*none.toml" "$T/nomanifest.log" || fail "the missing manifest unsaid"
grep -q "machine.toml:[0-9]*: pump: unknown section" "$T/nomanifest.log" || fail "the file's error not named"

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
