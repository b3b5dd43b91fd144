# SPDX-License-Identifier: Apache-2.0
# shellcheck shell=sh
# Sourced by both guests' setup scripts (tests/vm/guest-init.sh under busybox sh,
# tests/vm-systemd/guest-test.sh under bash). The caller defines setup_failed MESSAGE.
#
# make_gpio_sim_chip NAME LINE_NAME...: a gpio-sim chip made through configfs, labelled NAME (the
# tests and the daemon's configuration find it by that label, never by gpiochipN), one line per
# LINE_NAME at offsets 0, 1, ...
make_gpio_sim_chip() {
  gpio_sim_dir="/sys/kernel/config/gpio-sim/$1"
  shift
  mkdir "$gpio_sim_dir" "$gpio_sim_dir/bank0" ||
    setup_failed "cannot create gpio-sim chip $gpio_sim_dir"
  echo $# >"$gpio_sim_dir/bank0/num_lines"
  basename "$gpio_sim_dir" >"$gpio_sim_dir/bank0/label"
  gpio_sim_offset=0
  for gpio_sim_line in "$@"; do
    mkdir "$gpio_sim_dir/bank0/line$gpio_sim_offset"
    echo "$gpio_sim_line" >"$gpio_sim_dir/bank0/line$gpio_sim_offset/name"
    gpio_sim_offset=$((gpio_sim_offset + 1))
  done
  echo 1 >"$gpio_sim_dir/live" || setup_failed "cannot make gpio-sim chip $gpio_sim_dir live"
  echo "gpio-sim $(basename "$gpio_sim_dir"): $(cat "$gpio_sim_dir/dev_name")/$(cat "$gpio_sim_dir/bank0/chip_name") lines: $*"
}
