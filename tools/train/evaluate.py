#!/usr/bin/python3
"""Evaluates a segmentation ONNX model through OpenCV DNN on a list of images + class-id masks.

Preprocessing is the one the daemon's DnnModelSpec describes: the whole frame resized to the
input size with INTER_AREA (no aspect kept), channels swapped to RGB when spec.rgb, then
(pixel - mean_rgb) * scale. The argmax is taken at the network's resolution and scaled to the
mask's size with nearest neighbour (what the daemon sees).

Figures: IoU per class, MIoU, MPA (mean per-class pixel accuracy) as the wheat paper defines
them, and the sprayer's zone trade-off: each image cut into a rows x cols grid, a zone is weedy
when its true weed pixels are >= 0.5 % of it; for each decision threshold on the predicted weed
share, recall = weedy zones sprayed, clean_left_dry = weed-free zones left dry.

    /usr/bin/python3 tools/train/evaluate.py --model models/weed-peanut.onnx \
        --spec models/weed-peanut.json --images ../shared/data/peanut/images \
        --masks ../shared/data/peanut/masks --list tools/train/splits/peanut-val.txt
"""

import argparse
import json
import os
import statistics
import time

import cv2
import numpy as np

WEEDY_ZONE_SHARE = 0.005
ZONE_THRESHOLDS = (0.001, 0.0025, 0.005, 0.01, 0.02)
ZONE_RECALL_TARGET = 0.95
ZONE_GRID = (2, 4)  # rows, columns


def read_list(path):
    with open(path) as lines:
        stems = [line.strip() for line in lines if line.strip()]
    if not stems:
        raise SystemExit(f"{path}: empty list")
    return stems


def find_image(folder, stem):
    for suffix in (".jpg", ".jpeg", ".png", ".JPG", ".JPEG", ".PNG", ".bmp", ".tif", ".tiff"):
        path = os.path.join(folder, stem + suffix)
        if os.path.exists(path):
            return path
    raise SystemExit(f"--images {folder}: no image for '{stem}'")


def load_pair(images, masks, stem, classes):
    """(BGR image, class-id mask) of one stem; clear errors on missing files or bad ids."""
    image = cv2.imread(find_image(images, stem), cv2.IMREAD_COLOR)
    mask_path = os.path.join(masks, stem + ".png")
    mask = cv2.imread(mask_path, cv2.IMREAD_UNCHANGED)
    if image is None:
        raise SystemExit(f"--images: cannot read '{stem}'")
    if mask is None:
        raise SystemExit(f"--masks: cannot read {mask_path}")
    if mask.ndim != 2 or mask.shape != image.shape[:2]:
        raise SystemExit(f"{mask_path}: must be one channel of class ids, {image.shape[1]}x{image.shape[0]}")
    if int(mask.max()) >= classes:
        raise SystemExit(f"{mask_path}: class id {int(mask.max())} but only {classes} classes")
    return image, mask


def to_blob(bgr, spec):
    """N=1 x 3 x H x W float blob of a BGR frame, as the daemon prepares it."""
    size = (spec["input_width"], spec["input_height"])
    resized = cv2.resize(bgr, size, interpolation=cv2.INTER_AREA)
    return cv2.dnn.blobFromImage(resized, spec["scale"], size, tuple(spec["mean_rgb"]), swapRB=spec["rgb"])


def predict_labels(net, bgr, spec):
    net.setInput(to_blob(bgr, spec))
    labels = net.forward()[0].argmax(axis=0).astype(np.uint8)
    return cv2.resize(labels, (bgr.shape[1], bgr.shape[0]), interpolation=cv2.INTER_NEAREST)


class Scores:
    """Accumulates a confusion matrix and zone weed shares over images."""

    def __init__(self, classes, weed_class):
        self.classes = classes
        self.weed_class = weed_class
        self.confusion = np.zeros((classes, classes), np.int64)  # [truth, predicted]
        self.zone_truth = []
        self.zone_predicted = []

    def add(self, truth, predicted):
        index = truth.astype(np.int64).ravel() * self.classes + predicted.astype(np.int64).ravel()
        self.confusion += np.bincount(index, minlength=self.classes**2).reshape(self.classes, self.classes)
        self.zone_truth += zone_shares(truth == self.weed_class)
        self.zone_predicted += zone_shares(predicted == self.weed_class)

    def summary(self, names):
        tp = np.diag(self.confusion).astype(float)
        truth_total = self.confusion.sum(axis=1)
        predicted_total = self.confusion.sum(axis=0)
        iou = tp / np.maximum(truth_total + predicted_total - tp, 1)
        accuracy = tp / np.maximum(truth_total, 1)
        return {
            "iou": {name: round(float(v), 4) for name, v in zip(names, iou)},
            "miou": round(float(iou.mean()), 4),
            "pixel_accuracy": {name: round(float(v), 4) for name, v in zip(names, accuracy)},
            "mpa": round(float(accuracy.mean()), 4),
            "zones": zone_tradeoff(np.array(self.zone_truth), np.array(self.zone_predicted)),
        }


def zone_shares(flags):
    rows, cols = ZONE_GRID
    height, width = flags.shape
    shares = []
    for r in range(rows):
        for c in range(cols):
            zone = flags[r * height // rows : (r + 1) * height // rows, c * width // cols : (c + 1) * width // cols]
            shares.append(float(zone.mean()))
    return shares


def zone_tradeoff(truth_shares, predicted_shares):
    weedy = truth_shares >= WEEDY_ZONE_SHARE
    table = []
    for threshold in ZONE_THRESHOLDS:
        sprayed = predicted_shares >= threshold
        table.append(
            {
                "threshold": threshold,
                "recall": round(float(sprayed[weedy].mean()) if weedy.any() else 1.0, 4),
                "clean_left_dry": round(float((~sprayed[~weedy]).mean()) if (~weedy).any() else 1.0, 4),
            }
        )
    meeting = [row for row in table if row["recall"] >= ZONE_RECALL_TARGET]
    best = max(meeting, key=lambda row: row["clean_left_dry"]) if meeting else max(
        table, key=lambda row: row["recall"] + row["clean_left_dry"]
    )
    return {
        "grid": f"{ZONE_GRID[0]}x{ZONE_GRID[1]}",
        "weedy_zone_share": WEEDY_ZONE_SHARE,
        "weedy": int(weedy.sum()),
        "clean": int((~weedy).sum()),
        "thresholds": table,
        "best": dict(best, rule=f"most zones left dry with recall >= {ZONE_RECALL_TARGET}"
                     if meeting else "highest recall + clean_left_dry (no threshold reaches the recall target)"),
    }


def evaluate(net, spec, images, masks, stems):
    scores = Scores(len(spec["classes"]), spec["weed_class"])
    for stem in stems:
        image, mask = load_pair(images, masks, stem, len(spec["classes"]))
        scores.add(mask, predict_labels(net, image, spec))
    return dict(scores.summary(spec["classes"]), images=len(stems))


def median_forward_ms(net, spec, repeats=30):
    """Median ms of one forward pass at the input size, OpenCV DNN on one thread."""
    threads = cv2.getNumThreads()
    cv2.setNumThreads(1)
    blob = np.random.default_rng(0).standard_normal((1, 3, spec["input_height"], spec["input_width"]), np.float32)
    times = []
    for _ in range(repeats + 3):
        start = time.perf_counter()
        net.setInput(blob)
        net.forward()
        times.append((time.perf_counter() - start) * 1000.0)
    cv2.setNumThreads(threads)
    return round(statistics.median(times[3:]), 2)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--model", required=True, help="ONNX file")
    parser.add_argument("--spec", required=True, help="the model's JSON (its 'spec' object is used)")
    parser.add_argument("--images", required=True)
    parser.add_argument("--masks", required=True)
    parser.add_argument("--list", required=True, help="image stems to evaluate, one per line")
    parser.add_argument("--bench", action="store_true", help="also time one forward pass, one thread")
    args = parser.parse_args()
    with open(args.spec) as spec_file:
        spec = json.load(spec_file)["spec"]
    net = cv2.dnn.readNet(args.model)
    result = evaluate(net, spec, args.images, args.masks, read_list(args.list))
    if args.bench:
        result["forward_ms_1_thread"] = median_forward_ms(net, spec)
    print(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
