#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Every long option and subcommand that PROGRAM --help lists (and, for each subcommand,
# PROGRAM SUBCOMMAND... --help, to any depth), one a line after its subcommand path:
# `calibrate meter --seconds` is an option, `calibrate meter` a subcommand.
#   help_names.sh PROGRAM
set -euo pipefail
program="${1:?usage: help_names.sh PROGRAM}"
walk() { # ARGS...: the subcommand path
  local help
  help="$("$program" "$@" --help)" || { echo "help_names: '$program $* --help' failed" >&2; exit 1; }
  local option sub
  for option in $(grep -oE -- '^ +(-[A-Za-z], ?)?--[a-z][a-z0-9-]*' <<<"$help" | grep -oE -- '--[a-z][a-z0-9-]*'); do
    echo "${*:+$* }$option"
  done
  for sub in $(sed -n '/^Subcommands:/,/^$/p' <<<"$help" | grep -oE '^  [a-z][a-z0-9-]*' || true); do
    echo "${*:+$* }$sub"
    walk "$@" "$sub"
  done
}
walk
