#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# A full disk under the as-applied log while the simulated sprayer sprays: the warning
# records_disk_full is raised and shown in the status, spraying goes on, no line is torn; once
# space returns the lines held in memory are written in order (seq continuous) and the alarm
# clears itself. The log folder is a small tmpfs in a private mount namespace: needs root and
# unshare(1); skipped (77) where either is missing.
# usage: records_disk_full_sim_test.sh BUILD_DIR
set -euo pipefail
if [ -z "${RECORDS_TEST_IN_NAMESPACE:-}" ]; then
  if [ "$(id -u)" != 0 ] || ! unshare --mount true 2>/dev/null; then
    echo "skip: needs root and mount namespaces (unshare --mount)"
    exit 77
  fi
  RECORDS_TEST_IN_NAMESPACE=1 exec unshare --mount --propagation private "$0" "$@"
fi
BUILD=$(realpath "$1")
. "$(dirname "$0")/private_bus_lib.sh" records-disk-full  # $T and fail(); no bus is started
LOGS="$T/state/as-applied"
mkdir -p "$LOGS"
mount -t tmpfs -o size=256k tmpfs "$LOGS" || { echo "skip: cannot mount a tmpfs"; exit 77; }
unmount_logs() { umount "$LOGS"; }
EXIT_HOOKS+=(unmount_logs)
write_sim_config "[log]" "min_free_mb = 0"

resumed_sim daemon --run-seconds 60 &
DAEMON_PID=$!
wait_log "$T/daemon.log" "state Idle -> Spraying"
sleep 1  # some lines written before the disk fills
# Fill the disk to the last block: the next line lands short or not at all.
dd if=/dev/zero of="$LOGS/filler" bs=1k 2>/dev/null || true
wait_log "$T/daemon.log" "as-applied log: cannot write"
wait_log "$T/daemon.log" "alarm raised: records_disk_full"
wait_log "$T/daemon.log" "^Spraying .*ALARMS: records_disk_full"
sleep 2  # lines pile up in memory
rm "$LOGS/filler"
wait_log "$T/daemon.log" "as-applied log: writing again"
wait_log "$T/daemon.log" "alarm cleared: records_disk_full"
sleep 1
kill -TERM "$DAEMON_PID"
wait "$DAEMON_PID" || fail "the daemon did not stop in order"
DAEMON_PID=
grep -q -- "-> Fault" "$T/daemon.log" && fail "a full disk stopped the spraying"

# Every line whole (the header's column count, newline-ended), seq 1, 2, ... with no gap.
cat "$LOGS"/as-applied-*.csv >"$T/all.csv"
awk -F, '
  /^time_s,/ { columns = NF; next }
  NF != columns { print "torn line " NR ": " $0; bad = 1 }
  { if ($NF != ++seq) { print "seq " $NF " where " seq " was due"; bad = 1; seq = $NF } }
  END { if (seq < 20) { print "only " seq " lines"; bad = 1 } exit bad }
' "$T/all.csv" || fail "as-applied lines torn or missing"
[ "$(tail -c1 "$T/all.csv" | od -An -c | tr -d ' ')" = '\n' ] || fail "last line torn"
echo "ok: full disk while spraying: alarm raised and cleared, $(grep -vc '^time_s' "$T/all.csv") whole lines, seq continuous"
