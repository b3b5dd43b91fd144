#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Writes the turn-compensation test's track: NMEA 0183 at 5 Hz (RMC, GGA, GSA each epoch) for
gpsfake to feed a real gpsd in real time (3 sentences an epoch at `gpsfake -c 0.0667`). The
vehicle drives north at 2 m/s, turns 90 degrees right on an exact 12 m circle (the positions lie
on the circle, the course is its tangent), drives east, and stops, as at a headland. A CSV of
the epochs (UTC, latitude, longitude, speed, course, segment) goes beside it.

    tools/gnss/make_turn_track.py tests/data/gnss   # writes turn_track.nmea and turn_track.csv

Deterministic: the committed files are this script's output, byte for byte.
"""
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from make_track import EARTH_RADIUS_M, START_LAT, START_LON, fix_sentences  # noqa: E402

DATE = "250626"  # ddmmyy
START_S = 15 * 3600  # 15:00:00 UTC
STEP_S = 0.2
SPEED = 2.0
RADIUS = 12.0
STRAIGHT_S = 8.0
TURN_S = (math.pi / 2) * RADIUS / SPEED  # 9.42 s
STOP_S = 3.0


def pose(t):
    """(north m, east m, speed, course deg, segment) at t seconds after the start."""
    if t < STRAIGHT_S:
        return SPEED * t, 0.0, SPEED, 0.0, "straight"
    north0 = SPEED * STRAIGHT_S
    if t < STRAIGHT_S + TURN_S:  # right turn: the circle's centre is RADIUS east of the start
        theta = SPEED * (t - STRAIGHT_S) / RADIUS
        return (north0 + RADIUS * math.sin(theta), RADIUS - RADIUS * math.cos(theta), SPEED,
                math.degrees(theta), "turn")
    t2 = t - STRAIGHT_S - TURN_S
    north1, east1 = north0 + RADIUS, RADIUS
    if t2 < STRAIGHT_S:
        return north1, east1 + SPEED * t2, SPEED, 90.0, "straight"
    return north1, east1 + SPEED * STRAIGHT_S, 0.0, 90.0, "stop"


def main():
    out_dir = sys.argv[1] if len(sys.argv) > 1 else "tests/data/gnss"
    nmea_lines = ["# weedspray turn test track, written by tools/gnss/make_turn_track.py"]
    csv_lines = ["utc,lat_deg,lon_deg,speed_m_per_s,course_deg,segment"]
    epochs = int(round((2 * STRAIGHT_S + TURN_S + STOP_S) / STEP_S))
    for k in range(epochs + 1):
        t = k * STEP_S
        north, east, speed, course, segment = pose(t)
        lat = START_LAT + math.degrees(north / EARTH_RADIUS_M)
        lon = START_LON + math.degrees(east / (EARTH_RADIUS_M * math.cos(math.radians(START_LAT))))
        centis = int(round((START_S + t) * 100))
        s = centis // 100
        stamp = "%02d%02d%02d.%02d" % (s // 3600, s // 60 % 60, s % 60, centis % 100)
        nmea_lines += fix_sentences(stamp, lat, lon, speed, course, DATE, "%.2f")
        iso = "20%s-%s-%sT%s:%s:%s.%sZ" % (DATE[4:6], DATE[2:4], DATE[0:2], stamp[0:2],
                                           stamp[2:4], stamp[4:6], stamp[7:9])
        csv_lines.append("%s,%.9f,%.9f,%.3f,%.2f,%s" % (iso, lat, lon, speed, course, segment))
    os.makedirs(out_dir, exist_ok=True)
    with open(os.path.join(out_dir, "turn_track.nmea"), "w", newline="\r\n") as f:
        f.write("\n".join(nmea_lines) + "\n")
    with open(os.path.join(out_dir, "turn_track.csv"), "w") as f:
        f.write("\n".join(csv_lines) + "\n")


if __name__ == "__main__":
    main()
