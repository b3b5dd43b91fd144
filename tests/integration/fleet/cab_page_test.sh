#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The cab page in Debian's headless Chromium, driven over the DevTools protocol (cdp.py): three
# weedsprayd --sim boards with their fleet bridges on a loopback mosquitto, weedspray-cab serving
# the page. The page shows every board; Start (then its confirmation) on the page -> every board
# Spraying within 1 s (over D-Bus); a dose set on the page -> every board's TargetRate, and the
# page shows it on every card; a board's bridge killed -> the page shows it lost within 3 s;
# Stop on the page -> every board left Idle with its valves closed; every card shows its
# board's live-view picture, served by the cab as a PNG.
# usage: cab_page_test.sh BUILD_DIR SOURCE_DIR
set -euo pipefail
BUILD=$(realpath "$1")
SOURCE=$(realpath "$2")
PY=/usr/bin/python3
CDP="$PY $(dirname "$(realpath "$0")")/cdp.py"
. "$(dirname "$0")/fleet_lib.sh" cab
BOARDS=(1 2 3)

page() { $CDP "$T/chrome" "$1"; }  # page EXPRESSION -> its value as JSON
# The boards the page shows, with their state: "b1:Idle b2:Idle ..." in boom order.
page_boards() {
  page '[...document.querySelectorAll(".board")].map(b => b.dataset.board + ":" + b.dataset.state).join(" ")' |
    tr -d '"'
}
wait_page() {  # wait_page REGEX SECONDS: until page_boards matches
  local shown _
  for _ in $(seq 1 $(($2 * 10))); do
    shown=$(page_boards 2>/dev/null || true)
    [[ "$shown" =~ $1 ]] && return 0
    sleep 0.1
  done
  fail "the page shows '$shown', expected /$1/ within $2 s"
}

start_broker
make_green_field
CAB_PORT=$($PY -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])')
for n in "${BOARDS[@]}"; do
  write_board_config "$n" "[cab]" "listen_address = \"127.0.0.1\"" "port = $CAB_PORT"
  start_board "$n"
done
for n in "${BOARDS[@]}"; do wait_board_state "$n" Idle 30; done
for n in "${BOARDS[@]}"; do start_bridge "$n"; done

"$BUILD/cab/weedspray-cab" --config "$T/b1/weedspray.toml" --web-dir "$SOURCE/cab/web" >"$T/cab.log" 2>&1 &
PIDS+=($!)
for _ in $(seq 1 50); do
  $PY -c 'import sys, urllib.request; urllib.request.urlopen(sys.argv[1], timeout=1)' \
    "http://127.0.0.1:$CAB_PORT/api/machine" 2>/dev/null && break
  sleep 0.1
done
chromium --headless=new --no-sandbox --disable-gpu --no-first-run --remote-debugging-port=0 \
  --remote-allow-origins='*' --user-data-dir="$T/chrome" "http://127.0.0.1:$CAB_PORT/" \
  >"$T/chromium.log" 2>&1 &
PIDS+=($!)
for _ in $(seq 1 300); do
  [ -s "$T/chrome/DevToolsActivePort" ] && break
  sleep 0.1
done
[ -s "$T/chrome/DevToolsActivePort" ] || fail "chromium never opened its DevTools port"

wait_page '^b1:Idle b2:Idle b3:Idle$' 20
echo "ok: the page shows the three boards Idle, in boom order"

# Every board's live-view picture: served as a PNG (404 for a board without one), and shown on
# its card as an <img> that loaded.
for n in "${BOARDS[@]}"; do retained_picture "$n" "$T/picture$n.png" >/dev/null; done
$PY - "http://127.0.0.1:$CAB_PORT" <<'PYEOF' || fail "the cab's pictures"
import sys, time, urllib.error, urllib.request
base = sys.argv[1]
for n in (1, 2, 3):
    for _ in range(50):
        try:
            reply = urllib.request.urlopen(f"{base}/api/board/b{n}/picture.png", timeout=2)
            break
        except urllib.error.HTTPError:
            time.sleep(0.1)
    assert reply.headers["Content-Type"] == "image/png", reply.headers
    assert reply.headers["Cache-Control"] == "no-store", reply.headers
    assert reply.read()[:8] == b"\x89PNG\r\n\x1a\n"
try:
    urllib.request.urlopen(f"{base}/api/board/nosuch/picture.png", timeout=2)
    sys.exit("a picture for a board that sent none")
except urllib.error.HTTPError as error:
    assert error.code == 404, error.code
PYEOF
for _ in $(seq 1 50); do
  loaded=$(page '[...document.querySelectorAll(".board img.picture")].filter(i => i.complete && i.naturalWidth > 0).length')
  [ "$loaded" = 3 ] && break
  sleep 0.1
done
[ "$loaded" = 3 ] || fail "the page shows $loaded loaded pictures, expected 3"
echo "ok: every card shows its board's live-view picture ($(page 'document.querySelector(".board img.picture").naturalWidth') px wide)"

# Start is guarded: the first tap only asks.
page 'document.getElementById("start").click()' >/dev/null
sleep 0.5
for n in "${BOARDS[@]}"; do
  [ "$(board_prop "$n" State)" = '"Idle"' ] || fail "board $n started before the confirmation"
done
[ "$(page 'document.getElementById("confirm-bar").hidden')" = false ] || fail "no confirmation asked"
t0=$(now)
page 'document.getElementById("confirm").click()' >/dev/null
wait_all_spraying "$t0" "Start on the page"
echo "ok: every board Spraying ${took} s after Start was confirmed on the page"
wait_page '^b1:Spraying b2:Spraying b3:Spraying$' 3
# The nozzles are drawn as bars with the board's duties.
bars=$(page '[...document.querySelectorAll("[data-board=b1] .bar")].length')
[ "$bars" = 3 ] || fail "board 1 shows $bars nozzle bars, expected 3"

# The dose: typed on the page, set on every board (over D-Bus), shown back on every card.
page 'document.getElementById("dose").value = "120"; document.getElementById("set-dose").click()' \
  >/dev/null
for n in "${BOARDS[@]}"; do wait_board_prop "$n" TargetRate 120 3; done
for _ in $(seq 1 30); do
  doses=$(page '[...document.querySelectorAll(".board .dose b")].map(b => b.textContent).join(" ")' |
    tr -d '"')
  [ "$doses" = "120 120 120" ] && break
  sleep 0.1
done
[ "$doses" = "120 120 120" ] || fail "the cards show the doses '$doses', expected 120 each"
echo "ok: a dose set on the page reached every board and shows on every card"

# A board lost: its bridge killed.
kill -KILL "${BRIDGE_PID[2]}"
t0=$(now)
wait_page '^b1:Spraying b2:LOST b3:Spraying$' 3
echo "ok: the page shows board 2 lost $(elapsed_since "$t0") s after its bridge was killed"

# Stop on the page: no confirmation, every board still reachable stops.
page 'document.getElementById("stop").click()' >/dev/null
for n in 1 3; do
  wait_board_closed "$n" 1
done
wait_page '^b1:Idle b2:LOST b3:Idle$' 3
echo "ok: Stop on the page closed every board"
echo "PASS"
