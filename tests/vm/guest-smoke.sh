#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# Guest program: proves the kernel side with Debian's own tools before the project's classes
# are tested (an error here points at the harness, not at weedspray's io code).
#   - a line driven by gpioset shows up in gpio-sim's sim_gpioN/value
#   - a sim_gpioN/pull change is what gpioget reads
#   - vivid streams 640x360 YUYV frames through mmap
set -u
failures=0
check() { # DESCRIPTION COMMAND...
  description="$1"
  shift
  if "$@"; then echo "smoke: ok   $description"; else
    echo "smoke: FAIL $description"
    failures=$((failures + 1))
  fi
}

chip_of() { cat "/sys/kernel/config/gpio-sim/$1/bank0/chip_name"; }
sim_line() { # CHIP_CONFIG_NAME OFFSET -> sysfs dir of the simulated line
  echo "/sys/devices/platform/$(cat "/sys/kernel/config/gpio-sim/$1/dev_name")/$(chip_of "$1")/sim_gpio$2"
}
value_is() { [ "$(cat "$1/value")" = "$2" ]; }

out_chip="$(chip_of weedspray-out)"
in_chip="$(chip_of weedspray-in)"
check "gpioinfo names valve2 on $out_chip" sh -c "gpioinfo $out_chip | grep -q '\"valve2\"'"

gpioset --mode=signal "$out_chip" 2=1 &
holder=$!
sleep 0.3
check "gpioset valve2=1 is seen in sim_gpio2/value" value_is "$(sim_line weedspray-out 2)" 1
kill "$holder"
wait "$holder" 2>/dev/null

echo pull-up >"$(sim_line weedspray-in 1)/pull"
check "pull-up on wheel reads 1 with gpioget" sh -c "[ \"\$(gpioget $in_chip 1)\" = 1 ]"
echo pull-down >"$(sim_line weedspray-in 1)/pull"
check "pull-down on wheel reads 0 with gpioget" sh -c "[ \"\$(gpioget $in_chip 1)\" = 0 ]"

for video in /dev/video*; do break; done
check "vivid streams 5 frames of 640x360 YUYV" \
  v4l2-ctl -d "$video" --set-fmt-video=width=640,height=360,pixelformat=YUYV \
  --stream-mmap --stream-count=5 --stream-to=/dev/null

[ "$failures" -eq 0 ]
