#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""Drives a headless Chromium's page over the DevTools protocol (Debian's python3-websocket).

usage: cdp.py PROFILE_DIR EXPRESSION
Evaluates the JavaScript EXPRESSION in the first page of the Chromium whose --user-data-dir is
PROFILE_DIR (started with --remote-debugging-port=0, so its port is in DevToolsActivePort) and
prints the result as JSON. Exit status 1 when the expression throws.
"""
import json
import pathlib
import sys
import urllib.request

import websocket


def page_socket(profile):
    port = (pathlib.Path(profile) / "DevToolsActivePort").read_text().split()[0]
    with urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list", timeout=5) as response:
        targets = json.load(response)
    page = next(t for t in targets if t["type"] == "page")
    return websocket.create_connection(page["webSocketDebuggerUrl"], timeout=10)


def evaluate(profile, expression):
    ws = page_socket(profile)
    try:
        ws.send(json.dumps({"id": 1, "method": "Runtime.evaluate",
                            "params": {"expression": expression, "returnByValue": True,
                                       "awaitPromise": True}}))
        while True:
            reply = json.loads(ws.recv())
            if reply.get("id") == 1:
                break
    finally:
        ws.close()
    result = reply.get("result", {})
    if "exceptionDetails" in result:
        print(json.dumps(result["exceptionDetails"].get("text")), file=sys.stderr)
        return 1
    print(json.dumps(result.get("result", {}).get("value")))
    return 0


if __name__ == "__main__":
    sys.exit(evaluate(sys.argv[1], sys.argv[2]))
