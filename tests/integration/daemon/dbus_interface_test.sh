#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The shipped interface description (systemd/org.weedspray.Sprayer1.xml, installed under
# /usr/share/dbus-1/interfaces for code generators and D-Bus browsers) is what weedsprayd
# serves: its org.weedspray.Sprayer1 element equals the daemon's own introspection on a
# private bus. With --write it rewrites the file from the daemon instead.
# usage: dbus_interface_test.sh BUILD_DIR SOURCE_DIR [--write]
set -euo pipefail
BUILD=$(realpath "$1")
SOURCE=$(realpath "$2")
WEEDSPRAYD=$BUILD/daemon/weedsprayd
SHIPPED=$SOURCE/systemd/org.weedspray.Sprayer1.xml
. "$(dirname "$0")/private_bus_lib.sh" dbus-interface

printf '%s\n' "[boom]" "nozzles = 2" >"$T/weedspray.toml"
start_private_bus
start_sim_daemon --run-seconds 30
busctl --user introspect --xml-interface org.weedspray.Sprayer1 /org/weedspray/Sprayer1 \
  >"$T/served.xml" || fail "introspection failed"
/usr/bin/python3 - "$T/served.xml" "$SHIPPED" "${3:-}" <<'PY' || fail "see above"
import sys
import xml.etree.ElementTree as ET

served_path, shipped_path, mode = sys.argv[1:]
NAME = "org.weedspray.Sprayer1"


def interface(root):
    found = [i for i in root.iter("interface") if i.get("name") == NAME]
    assert len(found) == 1, f"{len(found)} {NAME} interfaces"
    return found[0]


def canonical(element):
    # Attributes sorted, whitespace dropped: the same members in the same order compare equal.
    for e in element.iter():
        e.text = e.tail = None
    ET.indent(element, "  ")
    return ET.tostring(element, encoding="unicode")


served = canonical(interface(ET.parse(served_path).getroot()))
if mode == "--write":
    with open(shipped_path, "w") as out:
        out.write(
            '<!DOCTYPE node PUBLIC "-//freedesktop//DTD D-BUS Object Introspection 1.0//EN"\n'
            ' "http://www.freedesktop.org/standards/dbus/1.0/introspect.dtd">\n'
            "<!-- weedsprayd's D-Bus interface, as the daemon serves it on\n"
            "     /org/weedspray/Sprayer1 (docs/dbus.md says what each member means).\n"
            "     Written by tests/integration/daemon/dbus_interface_test.sh (its usage line\n"
            "     says how); the test daemon_dbus_interface keeps it equal to the daemon's. -->\n"
            "<node>\n" + "\n".join("  " + line for line in served.splitlines()) + "\n</node>\n")
    print(f"wrote {shipped_path}")
    sys.exit(0)
shipped = canonical(interface(ET.parse(shipped_path).getroot()))
if served != shipped:
    import difflib
    sys.stderr.writelines(difflib.unified_diff(shipped.splitlines(True), served.splitlines(True),
                                               "shipped", "served"))
    sys.exit(f"{shipped_path} differs from what weedsprayd serves: rewrite it with --write")
print(f"ok: {shipped_path} is the served interface")
PY
stop_daemon
