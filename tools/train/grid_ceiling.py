#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""How well can a network that decides every G mm of ground do at best? The masks themselves,
pooled to a G mm grid (each cell the class with most area) and enlarged back, scored against
the masks at the camera's scale: the IoU per class a perfect network deciding at that grid
would reach. A weed smaller than the grid cannot be drawn at all; choose a network's decision
grid (its class head's resolution, not its input's) from this before training one:

    /usr/bin/python3 tools/train/grid_ceiling.py --masks ../shared/data/peanut/masks \
        --list tools/train/splits/peanut-val-unshared.txt --dataset-mm-per-px 0.31 \
        --frame-mm-per-px 1.0077 --grid-mm 2,4,8

A plain network of tools/train decides at twice its input's ground scale (its class head runs
at half the input's resolution); a --detail K network at K times its input's.
"""

import argparse
import json
import os
import sys

import cv2
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from evaluate import IGNORE, read_list  # noqa: E402


def pooled_labels(mask, classes, size):
    """mask (class ids, 255 unlabelled) pooled to size by the class with most area, then
    enlarged back to the mask's size (nearest)."""
    shares = np.stack([(mask == c).astype(np.float32) for c in range(classes)], axis=-1)
    small = cv2.resize(shares, size, interpolation=cv2.INTER_AREA)
    if small.ndim == 2:
        small = small[..., None]
    labels = small.argmax(axis=-1).astype(np.uint8)
    return cv2.resize(labels, (mask.shape[1], mask.shape[0]), interpolation=cv2.INTER_NEAREST)


def grid_iou(masks, classes, mask_mm_per_px, grid_mm):
    """IoU per class of the masks against themselves pooled to grid_mm."""
    confusion = np.zeros((classes, classes), np.int64)
    for mask in masks:
        factor = mask_mm_per_px / grid_mm
        size = (max(1, round(mask.shape[1] * factor)), max(1, round(mask.shape[0] * factor)))
        predicted = pooled_labels(mask, classes, size)
        labelled = mask != IGNORE
        index = mask[labelled].astype(np.int64) * classes + predicted[labelled]
        confusion += np.bincount(index, minlength=classes**2).reshape(classes, classes)
    tp = np.diag(confusion)
    return tp / np.maximum(confusion.sum(0) + confusion.sum(1) - tp, 1)


def parse_args(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--masks", required=True, help="folder of STEM.png class-id masks (255 = unlabelled)")
    parser.add_argument("--list", required=True, help="stems to score, one per line")
    parser.add_argument("--dataset-mm-per-px", type=float, required=True, help="ground mm per mask pixel")
    parser.add_argument("--frame-mm-per-px", type=float,
                        help="score at this camera's scale (default: the masks' own)")
    parser.add_argument("--grid-mm", default="2,4,8", help="decision grids to score, mm, comma-separated")
    parser.add_argument("--classes", default="soil,crop,weed", help="class names in class-id order")
    return parser.parse_args(argv)


def main(argv=None):
    args = parse_args(argv)
    names = args.classes.split(",")
    try:
        grids = [float(g) for g in args.grid_mm.split(",")]
    except ValueError:
        raise SystemExit(f"--grid-mm '{args.grid_mm}': expected numbers, e.g. 2,4,8")
    if args.dataset_mm_per_px <= 0 or (args.frame_mm_per_px is not None and args.frame_mm_per_px <= 0) or \
            min(grids) <= 0:
        raise SystemExit("--dataset-mm-per-px, --frame-mm-per-px and --grid-mm must be > 0")
    frame_mm = args.frame_mm_per_px or args.dataset_mm_per_px
    masks = []
    for stem in read_list(args.list):
        path = os.path.join(args.masks, stem + ".png")
        mask = cv2.imread(path, cv2.IMREAD_UNCHANGED)
        if mask is None or mask.ndim != 2:
            raise SystemExit(f"--masks: cannot read {path} as one channel of class ids")
        factor = args.dataset_mm_per_px / frame_mm
        size = (max(1, round(mask.shape[1] * factor)), max(1, round(mask.shape[0] * factor)))
        masks.append(cv2.resize(mask, size, interpolation=cv2.INTER_NEAREST))
    rows = []
    for grid in grids:
        iou = grid_iou(masks, len(names), frame_mm, grid)
        rows.append({"grid_mm": grid, "iou": {n: round(float(v), 4) for n, v in zip(names, iou)},
                     "miou": round(float(iou.mean()), 4)})
    print(json.dumps({"masks": len(masks), "frame_mm_per_px": frame_mm, "grids": rows}, indent=2))


if __name__ == "__main__":
    main()
