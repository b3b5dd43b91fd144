#!/bin/bash
# SPDX-License-Identifier: Apache-2.0
# The alarm catalog: the committed journal catalog and docs/alarms.md are what weedsprayd
# prints, and journald's own tool indexes the catalog with one entry per alarm.
# Usage: alarm_catalog_test.sh WEEDSPRAYD SOURCE_DIR
set -euo pipefail
daemon="$1"
source_dir="$2"
T="$(mktemp -d)"
trap 'rm -rf "$T"' EXIT
fail() { echo "FAIL: $*"; exit 1; }

"$daemon" --print-alarm-catalog journal >"$T/weedspray.catalog"
"$daemon" --print-alarm-catalog markdown >"$T/alarms.md"
diff -u "$source_dir/systemd/weedspray.catalog" "$T/weedspray.catalog" ||
  fail "systemd/weedspray.catalog is stale: weedsprayd --print-alarm-catalog journal > systemd/weedspray.catalog"
diff -u "$source_dir/docs/alarms.md" "$T/alarms.md" ||
  fail "docs/alarms.md is stale: weedsprayd --print-alarm-catalog markdown > docs/alarms.md"

# journalctl --update-catalog in a scratch root, as systemd's package trigger runs it.
mkdir -p "$T/root/usr/lib/systemd/catalog" "$T/root/var/lib/systemd/catalog"
cp "$T/weedspray.catalog" "$T/root/usr/lib/systemd/catalog/"
journalctl --root="$T/root" --update-catalog
journalctl --root="$T/root" --list-catalog >"$T/list"
alarms="$(grep -c '^| `' "$T/alarms.md")"
listed="$(grep -c ' weedspray: alarm ' "$T/list" || true)"
[ "$alarms" -ge 18 ] || fail "only $alarms alarms in the Markdown table"
[ "$listed" = "$alarms" ] || fail "journalctl lists $listed weedspray entries for $alarms alarms: $(cat "$T/list")"
ids="$(grep -c '^-- [0-9a-f]\{32\}$' "$T/weedspray.catalog")"
unique="$(grep '^-- ' "$T/weedspray.catalog" | sort -u | wc -l)"
[ "$ids" = "$alarms" ] && [ "$unique" = "$alarms" ] || fail "$ids message ids, $unique unique, for $alarms alarms"
echo "ok: $alarms alarms, each with its own MESSAGE_ID in journalctl's catalog index"
