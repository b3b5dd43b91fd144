#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Every key that `weedsprayd --print-default-config` writes appears in the man page
# weedspray.toml(5), under the same [section] heading.
#   man_config_keys_test.sh WEEDSPRAYD MANPAGE
set -euo pipefail
weedsprayd="${1:?usage: man_config_keys_test.sh WEEDSPRAYD MANPAGE}"
manpage="${2:?usage: man_config_keys_test.sh WEEDSPRAYD MANPAGE}"
page="$(LC_ALL=C MANWIDTH=250 man --no-hyphenation --no-justification -l "$manpage")"
# "section key" pairs: the page's section headings start a line, its keys (.TP tags) are
# indented 7 columns, their text further (or, for a short key, on the same line).
page_keys="$(awk '/^\[/ { section = $1 } /^       [a-z_0-9]/ && section { print section, $1 }' <<<"$page")"
config_keys="$("$weedsprayd" --print-default-config |
  awk '/^\[/ { section = $1 } /^(# ?)?[a-z_0-9]+ = / { sub(/^# ?/, ""); print section, $1 }')"
[ -n "$config_keys" ] || { echo "man_config_keys_test: no key in --print-default-config" >&2; exit 1; }
missing="$(comm -23 <(sort -u <<<"$config_keys") <(sort -u <<<"$page_keys"))"
if [ -n "$missing" ]; then
  echo "man_config_keys_test: keys not in $(basename "$manpage"):" >&2
  echo "$missing" >&2
  exit 1
fi
echo "man_config_keys_test: all $(wc -l <<<"$config_keys") keys are in $(basename "$manpage")"
