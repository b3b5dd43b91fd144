#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Writes the recorded GNSS track of the gpsd integration test: NMEA 0183 sentences (RMC, GGA,
GSA each second, GSV every 4 s) that gpsfake feeds to a real gpsd, and a CSV of the same epochs (UTC
time, latitude, longitude, altitude, speed, course) that the test compares the reader's fixes
with. The vehicle drives a straight run north, a 90-degree right turn on a 12 m radius, a
straight run east, then brakes and stands still, as a sprayer does at a headland.

    tools/gnss/make_track.py tests/data/gnss   # writes field_track.nmea and field_track.csv

Deterministic (no randomness): the committed files are this script's output; rerunning it
rewrites them byte for byte.
"""
import math
import os
import sys

EARTH_RADIUS_M = 6371008.8  # mean radius: metres to degrees near the start point
START_LAT, START_LON, ALT_M = 52.0, 5.0, 12.5
START = (14, 30, 0)  # UTC hh, mm, ss on DATE
DATE = "240626"  # ddmmyy
KNOTS_PER_M_S = 3600.0 / 1852.0
# (PRN, elevation deg, azimuth deg, SNR dB): all nine used in the fix.
SATELLITES = [(2, 45, 120, 40), (5, 30, 200, 38), (7, 60, 300, 42), (9, 15, 50, 35),
              (13, 70, 10, 44), (16, 25, 250, 36), (20, 40, 160, 39), (27, 55, 80, 41),
              (30, 20, 330, 34)]


def epochs():
    """(speed m/s, course deg) per second: straight, turn, straight, braking, standing."""
    out = [(2.0, 0.0)] * 10
    # 90 degrees at 2 m/s on a 12 m radius takes 2*pi*12/4/2 = 9.4 s: 9 deg/s for 10 s.
    out += [(2.0, 9.0 * (i + 1)) for i in range(10)]
    out += [(2.0, 90.0)] * 4
    out += [(1.5, 90.0), (1.0, 90.0), (0.5, 90.0)]
    out += [(0.0, 90.0)] * 5
    return out


def nmea(body):
    checksum = 0
    for ch in body:
        checksum ^= ord(ch)
    return "$%s*%02X" % (body, checksum)


def lat_field(lat):
    d = int(abs(lat))
    return "%02d%09.6f,%s" % (d, (abs(lat) - d) * 60.0, "N" if lat >= 0 else "S")


def lon_field(lon):
    d = int(abs(lon))
    return "%03d%09.6f,%s" % (d, (abs(lon) - d) * 60.0, "E" if lon >= 0 else "W")


def fix_sentences(stamp, lat, lon, speed, course, date, course_format="%.1f"):
    """One epoch's RMC, GGA and GSA: time hhmmss.ss, position, speed m/s, course, date ddmmyy."""
    return [
        nmea(("GPRMC,%s,A,%s,%s,%.3f," + course_format + ",%s,,,A") % (
            stamp, lat_field(lat), lon_field(lon), speed * KNOTS_PER_M_S, course, date)),
        nmea("GPGGA,%s,%s,%s,1,09,0.8,%.1f,M,46.9,M,," % (
            stamp, lat_field(lat), lon_field(lon), ALT_M)),
        nmea("GPGSA,A,3,%s,,,,1.5,0.8,1.2" % ",".join(
            "%02d" % prn for prn, _, _, _ in SATELLITES)),
    ]


def main():
    out_dir = sys.argv[1] if len(sys.argv) > 1 else "tests/data/gnss"
    north = east = 0.0
    nmea_lines = ["# weedspray GNSS test track, written by tools/gnss/make_track.py"]
    csv_lines = ["utc,lat_deg,lon_deg,alt_m,speed_m_per_s,course_deg,segment"]
    hh, mm, ss = START
    for k, (speed, course) in enumerate(epochs()):
        if k > 0:  # position: move one second at this epoch's speed and course
            north += speed * math.cos(math.radians(course))
            east += speed * math.sin(math.radians(course))
        lat = START_LAT + math.degrees(north / EARTH_RADIUS_M)
        lon = START_LON + math.degrees(east / (EARTH_RADIUS_M * math.cos(math.radians(START_LAT))))
        t = hh * 3600 + mm * 60 + ss + k
        stamp = "%02d%02d%02d.00" % (t // 3600, t // 60 % 60, t % 60)
        segment = "straight" if k < 10 else "turn" if k < 20 else "straight" if k < 24 else (
            "braking" if speed > 0 else "stop")
        nmea_lines += fix_sentences(stamp, lat, lon, speed, course, DATE)
        if k % 4 == 3:  # the sky view every 4 s, as many receivers send it: gpsd's SKY report
            for i in range(0, len(SATELLITES), 4):
                body = ",".join("%02d,%02d,%03d,%02d" % sat for sat in SATELLITES[i:i + 4])
                nmea_lines.append(nmea("GPGSV,%d,%d,%02d,%s" % (
                    (len(SATELLITES) + 3) // 4, i // 4 + 1, len(SATELLITES), body)))
        iso = "20%s-%s-%sT%s:%s:%sZ" % (DATE[4:6], DATE[2:4], DATE[0:2], stamp[0:2], stamp[2:4],
                                        stamp[4:6])
        csv_lines.append("%s,%.8f,%.8f,%.1f,%.3f,%.1f,%s" % (iso, lat, lon, ALT_M, speed, course,
                                                             segment))
    os.makedirs(out_dir, exist_ok=True)
    with open(os.path.join(out_dir, "field_track.nmea"), "w", newline="\r\n") as f:
        f.write("\n".join(nmea_lines) + "\n")
    with open(os.path.join(out_dir, "field_track.csv"), "w") as f:
        f.write("\n".join(csv_lines) + "\n")


if __name__ == "__main__":
    main()
