# SPDX-License-Identifier: Apache-2.0
"""Synthetic field photos for the tools/train tests: brown soil, large light-green crop discs,
small dark-green weed blobs, sensor noise; masks 0 soil, 1 crop, 2 weed."""

import os

import cv2
import numpy as np

SOIL_BGR = (45, 80, 120)
CROP_BGR = (80, 200, 90)
WEED_BGR = (30, 120, 40)


def field_photo(seed, width=160, height=128):
    """(BGR photo, class-id mask) with two crop discs and three weed blobs."""
    rng = np.random.default_rng(seed)
    image = np.full((height, width, 3), SOIL_BGR, np.uint8)
    for _ in range(2):
        centre = (int(rng.integers(20, width - 20)), int(rng.integers(20, height - 20)))
        cv2.circle(image, centre, int(rng.integers(12, 20)), CROP_BGR, -1)
    for _ in range(3):
        centre = (int(rng.integers(5, width - 5)), int(rng.integers(5, height - 5)))
        axes = (int(rng.integers(3, 7)), int(rng.integers(2, 5)))
        cv2.ellipse(image, centre, axes, float(rng.uniform(0, 180)), 0, 360, WEED_BGR, -1)
    mask = np.zeros((height, width), np.uint8)
    mask[np.all(image == CROP_BGR, axis=2)] = 1
    mask[np.all(image == WEED_BGR, axis=2)] = 2
    noise = rng.normal(0, 6, image.shape)
    return np.clip(image + noise, 0, 255).astype(np.uint8), mask


def write_field(folder, stems, width=160, height=128, ignore_box=None):
    """Writes folder/images/STEM.png and folder/masks/STEM.png; ignore_box (x0, y0, x1, y1)
    marks that part of every mask 255. Returns (images folder, masks folder)."""
    images, masks = os.path.join(folder, "images"), os.path.join(folder, "masks")
    os.makedirs(images, exist_ok=True)
    os.makedirs(masks, exist_ok=True)
    for i, stem in enumerate(stems):
        image, mask = field_photo(i, width, height)
        if ignore_box:
            x0, y0, x1, y1 = ignore_box
            mask[y0:y1, x0:x1] = 255
        cv2.imwrite(os.path.join(images, stem + ".png"), image)
        cv2.imwrite(os.path.join(masks, stem + ".png"), mask)
    return images, masks


def write_list(path, stems):
    with open(path, "w") as out:
        out.write("".join(s + "\n" for s in stems))
    return path
