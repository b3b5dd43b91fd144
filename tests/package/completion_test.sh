#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The bash completions (tools/completion) in a fresh non-interactive bash: fixed cases, and
# every option and subcommand that `sprayctl --help` and `weedsprayd --help` list (to any
# depth) is offered where it may be typed. Run without the bash-completion package's helpers,
# and again with them where the package is installed.
#   completion_test.sh BUILD_DIR SOURCE_DIR
set -euo pipefail
build="${1:?usage: completion_test.sh BUILD_DIR SOURCE_DIR}"
source_dir="${2:?usage: completion_test.sh BUILD_DIR SOURCE_DIR}"
here="$(cd "$(dirname "$0")" && pwd)"
bash_completion=/usr/share/bash-completion/bash_completion

# A folder to complete file and folder names in.
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
mkdir "$work/state"
touch "$work/field.toml" "$work/shot.png"

helpers=""  # bash-completion's script, or empty for plain bash
# Prints COMPREPLY for LINE (the cursor at its end), sorted, one a line.
completions() {
  (cd "$work" && bash --norc --noprofile -c '
    [[ -z $1 ]] || source "$1"
    source "$2/tools/completion/sprayctl"
    source "$2/tools/completion/weedsprayd"
    line=$3
    read -r -a COMP_WORDS <<<"$line"
    [[ $line != *" " ]] || COMP_WORDS+=("")
    COMP_CWORD=$((${#COMP_WORDS[@]} - 1)) COMP_LINE=$line COMP_POINT=${#line}
    [[ $(complete -p "${COMP_WORDS[0]}") =~ -F\ ([^ ]+) ]] || exit 1
    COMPREPLY=()
    "${BASH_REMATCH[1]}" "${COMP_WORDS[0]}" "${COMP_WORDS[COMP_CWORD]}" "${COMP_WORDS[COMP_CWORD - 1]}"
    ((${#COMPREPLY[@]} == 0)) || printf "%s\n" "${COMPREPLY[@]}" | sort
  ' completion_test "$helpers" "$source_dir" "$1")
}

failures=0
fail() {
  echo "FAIL (${helpers:-plain bash}): $*" >&2
  failures=$((failures + 1))
}
# expect LINE WORD...: the completions of LINE are exactly WORDs.
expect() {
  local line=$1 got want=""
  shift
  got="$(completions "$line")"
  (($# == 0)) || want="$(printf '%s\n' "$@" | sort)"
  [[ $got == "$want" ]] || fail "'$line' gave [${got//$'\n'/ }], want [$*]"
}
# offers LINE WORD: WORD is among the completions of LINE.
offers() {
  grep -qxF -- "$2" <<<"$(completions "$1")" || fail "'$1' does not offer $2"
}

# Every name PROGRAM --help lists: a subcommand after its path, an option after its path and --.
covers() {
  local program=$1 names words n=0
  names="$("$here/help_names.sh" "$build/daemon/$program")"
  while read -r -a words; do
    ((${#words[@]})) || continue
    n=$((n + 1))
    local path="$program ${words[*]:0:${#words[@]}-1}"
    path="${path% } "
    if [[ ${words[-1]} == -* ]]; then
      offers "$path--" "${words[-1]}"
    else
      offers "$path" "${words[-1]}"
    fi
  done <<<"$names"
  ((n > 0)) || fail "no option found in '$program --help'"
  echo "completion_test: ${helpers:-plain bash}: $n names of $program --help checked"
}

run_cases() {
  expect "sprayctl st" start status stop
  expect "sprayctl calibrate " meter nozzles
  expect "sprayctl --user calibrate n" nozzles
  expect "sprayctl calibrate meter --" --help --seconds --volume
  expect "sprayctl status --" --help --json
  expect "sprayctl set-pressure --" --help
  expect "sprayctl set-" set-pressure set-rate set-threshold
  expect "sprayctl export-map --format " geojson gpkg shp
  expect "sprayctl export-map --dir " state
  expect "sprayctl snapshot --camera 1 sh" shot.png
  expect "sprayctl calibrate-wheel --distance " # a number: nothing
  expect "weedsprayd --print-alarm-catalog " journal markdown
  expect "weedsprayd --config fi" field.toml
  offers "weedsprayd --config " field.toml
  expect "weedsprayd --state-dir " state
  expect "weedsprayd --sim --sim-fault tank_e" tank_empty@
  expect "weedsprayd --check" --check-config
  expect "weedsprayd --run-seconds " # a number: nothing
  expect "weedsprayd " # options only after a -
  covers sprayctl
  covers weedsprayd
}

run_cases
if [[ -f $bash_completion ]]; then
  helpers=$bash_completion
  run_cases
else
  echo "completion_test: bash-completion not installed: checked in plain bash only"
fi
if ((failures)); then
  echo "completion_test: $failures failures" >&2
  exit 1
fi
echo "completion_test: all cases pass"
