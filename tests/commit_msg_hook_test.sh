#!/bin/sh
# SPDX-License-Identifier: Apache-2.0
# The commit-msg hook (.githooks/commit-msg) takes the project's subjects and refuses the rest.
hook="$1"
dir="$(mktemp -d)"
trap 'rm -rf "$dir"' EXIT
failures=0
check() { # EXPECTED_STATUS MESSAGE
  printf '%s\n' "$2" >"$dir/msg"
  "$hook" "$dir/msg" 2>/dev/null
  status=$?
  if [ "$status" -ne "$1" ]; then
    echo "FAIL: status $status (expected $1) for: $2"
    failures=$((failures + 1))
  fi
}
check 0 "vision: classify each plant by the network's votes"
check 0 "sim, lab: give the plant model and the experiments their own rooms"
check 0 "io/linux: read the E-stop line's edges on its own thread

Why, in the body."
check 0 "Merge branch 'estop'"
check 1 "Vision: capital area"
check 1 "classify plants"
check 1 "vision:no space"
check 1 "vision: ends with a full stop."
check 1 "control: $(printf 'x%.0s' $(seq 1 64))"
check 1 "vision: subject
body without the blank line"
check 1 "vision: several changes; bundled with a semicolon; $(printf 'y%.0s' $(seq 1 40))"
[ "$failures" -eq 0 ] && echo "commit-msg hook: all cases as expected"
exit "$failures"
