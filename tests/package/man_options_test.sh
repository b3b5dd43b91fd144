#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Every long option and subcommand that PROGRAM --help lists (and, for each subcommand,
# PROGRAM SUBCOMMAND... --help, to any depth) appears in the man page MANPAGE as rendered by man.
#   man_options_test.sh PROGRAM MANPAGE
set -euo pipefail
program="${1:?usage: man_options_test.sh PROGRAM MANPAGE}"
manpage="${2:?usage: man_options_test.sh PROGRAM MANPAGE}"
# ASCII rendering (LC_ALL=C), wide, without hyphenation: each name is on one line, as typed.
page="$(LC_ALL=C MANWIDTH=250 man --no-hyphenation --no-justification -l "$manpage")"
[ -n "$page" ] || { echo "man_options_test: $manpage renders empty" >&2; exit 1; }

names="$("$(dirname "$0")/help_names.sh" "$program")"
missing=()
checked=0
in_page() { grep -qE -- "(^|[^A-Za-z0-9-])$1([^A-Za-z0-9-]|$)" <<<"$page"; }
while read -r -a words; do
  ((${#words[@]})) || continue
  checked=$((checked + 1))
  kind=""
  [[ ${words[-1]} == -* ]] || kind=" (subcommand)"
  in_page "${words[-1]}" || missing+=("${words[*]}$kind")
done <<<"$names"
((checked > 0)) || { echo "man_options_test: no option found in '$program --help'" >&2; exit 1; }
if ((${#missing[@]})); then
  echo "man_options_test: not in $(basename "$manpage"):" >&2
  printf '  %s\n' "${missing[@]}" >&2
  exit 1
fi
echo "man_options_test: all $checked options and subcommands of $(basename "$program") are in $(basename "$manpage")"
