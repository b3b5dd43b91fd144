# SPDX-License-Identifier: Apache-2.0
"""The shared data sets' table (datasets.json) and what is read from it.

- training_data_entry: the {images, count, licence, attribution} record of a training folder,
  with the licence of the table's entry when the folder is one of its sets.
- model_licence: the licence line of a model learnt from such records (CC BY-SA 4.0 data make
  the model CC BY-SA 4.0: the data sets' READMEs say so).
- plant_soil_mask: a set's mask as the base network's classes (0 soil, 1 plant, 255 ignore);
  in sets that label only the crop, pixels of the soil value that look green (excess green
  2G - R - B above Otsu's level on the photo, at most GREEN_LEVEL_CAP, grown by GREEN_MARGIN_PX)
  are unlabelled weeds and become ignore.
"""

import json
import os

import cv2
import numpy as np

IGNORE = 255
HERE = os.path.dirname(os.path.abspath(__file__))
REPO_ROOT = os.path.dirname(os.path.dirname(HERE))
TABLE = os.path.join(HERE, "datasets.json")
UNKNOWN_LICENCE = "unknown: state it"
GREEN_LEVEL_CAP = 40
GREEN_MARGIN_PX = 2
BASE_CLASSES = ("soil", "plant")


def load_table(path=TABLE, data_root=None):
    """The table's sets, each with abs_path: the set's folder (path is relative to the
    repository root; data_root, when given, replaces the folder above each set)."""
    with open(path) as text:
        sets = json.load(text)["datasets"]
    for entry in sets:
        if data_root:
            entry["abs_path"] = os.path.join(data_root, os.path.basename(entry["path"]))
        else:
            entry["abs_path"] = os.path.normpath(os.path.join(REPO_ROOT, entry["path"]))
    return sets


def find_dataset(images_folder, table=None):
    """The table entry whose folder (or its images subfolder) is images_folder, else None."""
    wanted = os.path.realpath(images_folder)
    for entry in table if table is not None else load_table():
        folder = os.path.realpath(entry["abs_path"])
        if wanted in (folder, os.path.realpath(os.path.join(folder, entry["images"]))):
            return entry
    return None


def training_data_entry(images_folder, count, licence=None, attribution=None, table=None):
    entry = find_dataset(images_folder, table)
    if entry is not None:
        return {"images": entry["path"], "count": count, "licence": entry["licence"],
                "attribution": entry["attribution"]}
    return {"images": os.path.abspath(images_folder), "count": count,
            "licence": licence or UNKNOWN_LICENCE, "attribution": attribution or UNKNOWN_LICENCE}


def model_licence(records):
    """One line: the licence a model learnt from these training_data records carries."""
    share_alike = [r for r in records if "BY-SA" in r["licence"]]
    others = sorted({f"{r['licence']} ({r['images']})" for r in records if r not in share_alike})
    if share_alike:
        names = ", ".join(sorted({os.path.basename(r["images"].rstrip("/")) for r in share_alike}))
        line = f"CC BY-SA 4.0 (learnt from CC BY-SA 4.0 data: {names}; attribution in training_data)"
        return line + (f"; also learnt from: {'; '.join(others)}" if others else "")
    return "; ".join(others) if others else UNKNOWN_LICENCE


def green_mask(bgr):
    """Pixels a colour index calls green: 2G - R - B above min(Otsu's level, GREEN_LEVEL_CAP),
    grown by GREEN_MARGIN_PX."""
    b, g, r = (bgr[..., i].astype(np.int16) for i in range(3))
    exg = np.clip(2 * g - r - b, 0, 255).astype(np.uint8)
    otsu, _ = cv2.threshold(exg, 0, 255, cv2.THRESH_BINARY + cv2.THRESH_OTSU)
    green = (exg > min(otsu, GREEN_LEVEL_CAP)).astype(np.uint8)
    kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * GREEN_MARGIN_PX + 1,) * 2)
    return cv2.dilate(green, kernel) > 0


def plant_soil_mask(entry, bgr, mask):
    """A set's mask in the base classes: 0 soil, 1 plant, 255 ignore (see the module docstring)."""
    table = {"soil": 0, "plant": 1, "ignore": IGNORE}
    lut = np.full(256, IGNORE, np.uint8)
    for value, name in entry["plant_soil"].items():
        lut[int(value)] = table[name]
    out = lut[mask]
    if entry.get("green_unlabelled_is_ignore"):
        out[(out == 0) & green_mask(bgr)] = IGNORE
    return out
