#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Checks a map exported by weedspray-export-map (as GeoJSON: gnss_sim_test.sh converts the
GeoPackage and Shapefile exports with ogr2ogr) against the as-applied log it came from and the
NMEA track the daemon drove:
  - every sprayed polygon vertex lies near the track (WGS84 lon/lat order, right place);
  - each polygon is a strip one nozzle width wide (across the heading); its attributes agree (rate = volume/area,
    area at most max-stretch x width);
  - the end of each stretch sits where the antenna offsets put its nozzle: ahead/right of the
    nozzle in the log's antenna position and course at the stretch's utc_end, to 2 cm;
  - the weed_density cells are cell-size squares whose samples add up to the log's
    positioned nozzle records.
usage: map_check.py SPRAYED.geojson WEED_DENSITY.geojson LOG_DIR TRACK.nmea AHEAD_M RIGHT_M
"""
import csv
import glob
import json
import math
import sys

R = 6371008.8
sprayed_file, density_file, log_dir, nmea, ahead, right = sys.argv[1:7]
ahead, right = float(ahead), float(right)
failures = []


def check(ok, message):
    if not ok:
        failures.append(message)


def local(origin, lon, lat):  # metres east, north of origin (lon, lat)
    return (math.radians(lon - origin[0]) * R * math.cos(math.radians(origin[1])),
            math.radians(lat - origin[1]) * R)


def nmea_degrees(value, hemisphere):
    d = int(float(value) / 100)
    deg = d + (float(value) - 100 * d) / 60
    return -deg if hemisphere in "SW" else deg


track = []
for line in open(nmea):
    f = line.split(",")
    if f[0].endswith("RMC") and f[2] == "A":
        track.append((nmea_degrees(f[5], f[6]), nmea_degrees(f[3], f[4])))
origin = track[0]
track_xy = [local(origin, *p) for p in track]


def distance_to_track(x, y):
    best = float("inf")
    for (ax, ay), (bx, by) in zip(track_xy, track_xy[1:]):
        dx, dy = bx - ax, by - ay
        t = 0 if dx == dy == 0 else max(0, min(1, ((x - ax) * dx + (y - ay) * dy) / (dx * dx + dy * dy)))
        best = min(best, math.hypot(x - ax - t * dx, y - ay - t * dy))
    return best


rows = []
for path in sorted(glob.glob(log_dir + "/as-applied-*.csv")):
    rows += [r for r in csv.DictReader(open(path)) if r.get("latitude_deg")]
nozzles = sum(1 for k in rows[0] if k.startswith("duty_pct_"))
width = float(rows[0]["nozzle_width_m"])


def utc_key(text):
    """A UTC time as integer milliseconds. GDAL's GeoJSON reader takes string fields that look
    like times for DateTime fields and writes a whole second without its ".000" (ogr2ogr of a
    GeoJSON export): the same instant, another text."""
    whole, _, fraction = text.rstrip("Z").partition(".")
    return (whole, int((fraction + "000")[:3]) if fraction else 0)


by_utc = {utc_key(r["utc"]): r for r in rows}
offsets = [(n - (nozzles - 1) / 2) * width for n in range(nozzles)]

sprayed = json.load(open(sprayed_file))["features"]
check(len(sprayed) > 0, "no sprayed polygons")
fields = {"nozzle", "utc_start", "utc_end", "rate_l_ha", "volume_l", "area_m2", "duty_pct",
          "weed_dens", "crop_dens", "speed_m_s"}
placed = 0
for f in sprayed:
    p = f["properties"]
    check(set(p) == fields, "fields %s" % sorted(p))
    ring = f["geometry"]["coordinates"][0]
    xy = [local(origin, lon, lat) for lon, lat in ring]
    far = max(distance_to_track(x, y) for x, y in xy)
    check(far < math.hypot(ahead, abs(right) + nozzles * width / 2) + 1.0,
          "nozzle %d polygon %.1f m from the track" % (p["nozzle"], far))
    # Left edge forward, right edge back: point k and point n-1-k are the two ends of the
    # nozzle's patch at one record, one nozzle width apart.
    n_pts = len(ring) - 1
    for k in range(n_pts // 2):
        (x0, y0), (x1, y1) = xy[k], xy[n_pts - 1 - k]
        check(abs(math.hypot(x1 - x0, y1 - y0) - width) < 0.002,
              "polygon %.4f m wide, nozzle width %.3f" % (math.hypot(x1 - x0, y1 - y0), width))
    check(0 < p["area_m2"] <= 2.0 * width * 1.001, "area_m2 %s" % p["area_m2"])
    check(abs(p["rate_l_ha"] - p["volume_l"] / p["area_m2"] * 1e4) < 1e-6 * max(1, p["rate_l_ha"]),
          "rate_l_ha %s vs volume/area" % p["rate_l_ha"])
    check(p["duty_pct"] > 0, "a sprayed stretch with duty 0")
    row = by_utc.get(utc_key(p["utc_end"]))
    check(row is not None, "utc_end %s is no record's utc" % p["utc_end"])
    if row is None:
        continue
    # The stretch's last edge: the 2 points where the left edge ends and the right edge ends.
    left_end, right_end = ring[n_pts // 2 - 1], ring[n_pts // 2]
    mid = local(origin, (left_end[0] + right_end[0]) / 2, (left_end[1] + right_end[1]) / 2)
    ant = local(origin, float(row["longitude_deg"]), float(row["latitude_deg"]))
    h = math.radians(float(row["course_deg"]))
    de, dn = mid[0] - ant[0], mid[1] - ant[1]
    forward = dn * math.cos(h) + de * math.sin(h)
    lateral = -dn * math.sin(h) + de * math.cos(h)
    want_lateral = offsets[p["nozzle"]] - right
    check(abs(forward + ahead) < 0.02 and abs(lateral - want_lateral) < 0.02,
          "nozzle %d stretch end %.3f m ahead, %.3f m right of the antenna; want %.3f, %.3f" %
          (p["nozzle"], forward, lateral, -ahead, want_lateral))
    placed += 1
check(placed == len(sprayed), "%d of %d stretches placed against the log" % (placed, len(sprayed)))

cells = json.load(open(density_file))["features"]
check(len(cells) > 0, "no weed_density cells")
samples = 0
for c in cells:
    p = c["properties"]
    check(set(p) == {"weed_dens", "crop_dens", "samples"}, "cell fields %s" % sorted(p))
    check(0 <= p["weed_dens"] <= 1 and 0 <= p["crop_dens"] <= 1, "cell densities %s" % p)
    xy = [local(origin, lon, lat) for lon, lat in c["geometry"]["coordinates"][0]]
    xs, ys = [x for x, _ in xy], [y for _, y in xy]
    check(abs(max(xs) - min(xs) - 2.0) < 0.001 and abs(max(ys) - min(ys) - 2.0) < 0.001,
          "cell %.3f x %.3f m" % (max(xs) - min(xs), max(ys) - min(ys)))
    samples += p["samples"]
check(samples == len(rows) * nozzles,
      "grid samples %d, positioned nozzle records %d" % (samples, len(rows) * nozzles))

for m in failures[:10]:
    print("map_check: " + m, file=sys.stderr)
if failures:
    sys.exit("map_check: %d failures (%s)" % (len(failures), sprayed_file))
print("map_check: %d stretches placed to 2 cm, %d cells, %d samples" % (placed, len(cells), samples))
