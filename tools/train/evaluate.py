#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""Evaluates a segmentation ONNX model through OpenCV DNN on a list of images + class-id masks.

Masks hold one class id per pixel; 255 marks unlabelled pixels, which no figure counts.

Preprocessing is the one the daemon applies (vision/weed_source.cpp network_input_size): the
whole frame shrunk by area averaging (area_shrink), channels swapped to RGB when spec.rgb, then
(pixel - mean_rgb) * scale. When both the model's ground scale (spec.ground_mm_per_px) and the
photos' (--dataset-mm-per-px) are known, the frame is resampled so that one input pixel covers
ground_mm_per_px (each side rounded to a multiple of spec.stride, aspect kept); otherwise it is
squeezed to the spec's input size. Each class's scores are enlarged bilinearly to the mask's
size and the argmax taken there (what the daemon sees).

Figures: IoU per class, MIoU, MPA (mean per-class pixel accuracy), each image's own IoU per
class (per_image; null where a class is neither in the image's labels nor predicted), and the
sprayer's zone figures. Each image is cut into a rows x cols grid (2 x 4); a zone is
- weedy when its true weed pixels are >= 0.5 % of its labelled pixels,
- crop_only when not weedy and its true crop pixels are >= 0.5 %,
- bare otherwise;
zones less than half labelled are left out. For each decision threshold on the predicted weed
share of a zone: recall (weedy zones sprayed), crop_only_left_dry, bare_left_dry and
clean_left_dry (all weed-free zones left dry); null where no zone is of that kind. The best
threshold leaves most crop_only zones dry while keeping recall >= 0.95 (what a farmer pays
for: weeds hit, herbicide kept off the crop). intervals: 95 % percentile bootstrap over images
(1000 resamples, seeded) of the IoU per class, MIoU and the zone figures at the best threshold.
With --limits, limits.py's two figures: the labels' plant outline with the model's choice of
class, and the model's outline with the labels' classes (which of the two holds the model back).

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

import limits

IGNORE = 255
WEEDY_ZONE_SHARE = 0.005
CROP_ZONE_SHARE = 0.005
MIN_LABELLED_ZONE_SHARE = 0.5
ZONE_THRESHOLDS = (0.001, 0.0025, 0.005, 0.01, 0.02)
ZONE_RECALL_TARGET = 0.95
ZONE_GRID = (2, 4)  # rows, columns
ZONE_FIGURES = ("recall", "crop_only_left_dry", "bare_left_dry", "clean_left_dry")
BOOTSTRAP_RESAMPLES = 1000
IMAGE_SUFFIXES = (".jpg", ".jpeg", ".png", ".JPG", ".JPEG", ".PNG", ".bmp", ".tif", ".tiff")


def read_list(path):
    with open(path) as lines:
        stems = [line.strip() for line in lines if line.strip()]
    if not stems:
        raise SystemExit(f"{path}: empty list")
    return stems


def find_image(folder, stem):
    for suffix in IMAGE_SUFFIXES:
        path = os.path.join(folder, stem + suffix)
        if os.path.exists(path):
            return path
    raise SystemExit(f"--images {folder}: no image for '{stem}'")


def load_pair(images, masks, stem, classes):
    """(BGR image, class-id mask) of one stem; 255 in the mask = unlabelled. Clear errors on
    missing files, size mismatches or ids that are not classes."""
    image = cv2.imread(find_image(images, stem), cv2.IMREAD_COLOR)
    mask_path = os.path.join(masks, stem + ".png")
    mask = cv2.imread(mask_path, cv2.IMREAD_UNCHANGED)
    if image is None:
        raise SystemExit(f"--images: cannot read '{stem}'")
    if mask is None:
        raise SystemExit(f"--masks: cannot read {mask_path}")
    if mask.ndim != 2 or mask.shape != image.shape[:2]:
        raise SystemExit(f"{mask_path}: must be one channel of class ids, {image.shape[1]}x{image.shape[0]}")
    ids = np.unique(mask)
    bad = ids[(ids >= classes) & (ids != IGNORE)]
    if bad.size:
        raise SystemExit(f"{mask_path}: class id {int(bad[0])} but only {classes} classes (255 = unlabelled)")
    return image, mask


def network_input_size(spec, frame_mm_per_px, width, height):
    """(width, height) of the network input for a width x height frame, as the daemon picks it."""
    model_mm = spec.get("ground_mm_per_px")
    if not model_mm or not frame_mm_per_px:
        return spec["input_width"], spec["input_height"]
    scale = frame_mm_per_px / model_mm
    stride = spec.get("stride", 32)
    return tuple(max(1, int(np.floor(side * scale / stride + 0.5))) * stride for side in (width, height))


def whole_factor(side, to):
    """The largest whole factor <= side / to that divides side (1 when none)."""
    return next((f for f in range(side // to, 1, -1) if side % f == 0), 1)


def area_shrink(bgr, size):
    """Area averaging as the daemon shrinks a frame (vision/weed_network.cpp): by a whole factor
    of each side that divides it first, then the rest (bilinear when it shrinks by less than
    half: its two taps cover every source pixel)."""
    step = (bgr.shape[1] // whole_factor(bgr.shape[1], size[0]), bgr.shape[0] // whole_factor(bgr.shape[0], size[1]))
    if step == (bgr.shape[1], bgr.shape[0]) or step == tuple(size):
        return cv2.resize(bgr, size, interpolation=cv2.INTER_AREA)
    whole = cv2.resize(bgr, step, interpolation=cv2.INTER_AREA)
    rest_under_half = step[0] <= 2 * size[0] and step[1] <= 2 * size[1]
    return cv2.resize(whole, size, interpolation=cv2.INTER_LINEAR if rest_under_half else cv2.INTER_AREA)


def to_blob(bgr, spec, size=None):
    """N=1 x 3 x H x W float blob of a BGR frame at size (default: the spec's input size)."""
    size = size or (spec["input_width"], spec["input_height"])
    shrinking = size[0] <= bgr.shape[1] and size[1] <= bgr.shape[0]
    resized = area_shrink(bgr, size) if shrinking else cv2.resize(bgr, size, interpolation=cv2.INTER_LINEAR)
    return cv2.dnn.blobFromImage(resized, spec["scale"], size, tuple(spec["mean_rgb"]), swapRB=spec["rgb"])


def predict_scores(net, bgr, spec, frame_mm_per_px=None):
    """classes x H x W scores of bgr at its own size: the network's, each enlarged bilinearly
    to the frame (pixel centres aligned) when the network scores coarser."""
    size = network_input_size(spec, frame_mm_per_px, bgr.shape[1], bgr.shape[0])
    net.setInput(to_blob(bgr, spec, size))
    scores = net.forward()[0]
    frame = (bgr.shape[1], bgr.shape[0])
    if scores.shape[1:] == (frame[1], frame[0]):
        return scores
    return np.stack([cv2.resize(plane, frame, interpolation=cv2.INTER_LINEAR) for plane in scores])


def predict_labels(net, bgr, spec, frame_mm_per_px=None):
    """Class ids of bgr at its own size, as the daemon gives them (vision/weed_network.cpp,
    classes_at): the argmax of the network's scores each enlarged bilinearly to the frame."""
    return predict_scores(net, bgr, spec, frame_mm_per_px).argmax(axis=0).astype(np.uint8)


def confusion_matrix(truth, predicted, classes):
    """classes x classes pixel counts [truth, predicted] over the labelled pixels."""
    labelled = truth != IGNORE
    index = truth[labelled].astype(np.int64) * classes + predicted[labelled].astype(np.int64)
    return np.bincount(index, minlength=classes**2).reshape(classes, classes)


def iou_per_class(confusion):
    """IoU per class; nan where the class is neither labelled nor predicted."""
    tp = np.diag(confusion).astype(float)
    union = confusion.sum(axis=0) + confusion.sum(axis=1) - tp
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(union > 0, tp / np.maximum(union, 1), np.nan)


def zone_cells(truth, predicted, crop_class, weed_class):
    """Per grid zone: (true weed share, true crop share, predicted weed share, counted); shares
    of the truth are over the zone's labelled pixels, the prediction's over all of them."""
    rows, cols = ZONE_GRID
    height, width = truth.shape
    cells = np.zeros((rows * cols, 4))
    for r in range(rows):
        for c in range(cols):
            window = (slice(r * height // rows, (r + 1) * height // rows),
                      slice(c * width // cols, (c + 1) * width // cols))
            zone, guess = truth[window], predicted[window]
            labelled = int((zone != IGNORE).sum())
            cells[r * cols + c] = (
                (zone == weed_class).sum() / max(labelled, 1),
                (zone == crop_class).sum() / max(labelled, 1),
                float((guess == weed_class).mean()) if guess.size else 0.0,
                labelled >= MIN_LABELLED_ZONE_SHARE * max(zone.size, 1),
            )
    return cells


def zone_kinds(cells):
    counted = cells[:, 3] > 0
    weedy = counted & (cells[:, 0] >= WEEDY_ZONE_SHARE)
    crop_only = counted & ~weedy & (cells[:, 1] >= CROP_ZONE_SHARE)
    bare = counted & ~weedy & ~crop_only
    return weedy, crop_only, bare


def _share(flags):
    return round(float(flags.mean()), 4) if flags.size else None


def zone_figures(cells, threshold):
    weedy, crop_only, bare = zone_kinds(cells)
    sprayed = cells[:, 2] >= threshold
    return {
        "threshold": threshold,
        "recall": _share(sprayed[weedy]),
        "crop_only_left_dry": _share(~sprayed[crop_only]),
        "bare_left_dry": _share(~sprayed[bare]),
        "clean_left_dry": _share(~sprayed[crop_only | bare]),
    }


def _or(value, fallback):
    return fallback if value is None else value


def zone_tradeoff(cells):
    """The zone table over all thresholds and the best threshold by the farmer's rule."""
    weedy, crop_only, bare = zone_kinds(cells)
    table = [zone_figures(cells, threshold) for threshold in ZONE_THRESHOLDS]
    meeting = [row for row in table if _or(row["recall"], 1.0) >= ZONE_RECALL_TARGET]
    if meeting:
        best = max(meeting, key=lambda row: (_or(row["crop_only_left_dry"], _or(row["clean_left_dry"], 0.0)),
                                             _or(row["clean_left_dry"], 0.0)))
        rule = f"most crop_only zones left dry with recall >= {ZONE_RECALL_TARGET}"
    else:
        best = max(table, key=lambda row: (_or(row["recall"], 1.0), _or(row["crop_only_left_dry"], 0.0)))
        rule = "highest recall, then most crop_only zones left dry (no threshold reaches the recall target)"
    return {
        "grid": f"{ZONE_GRID[0]}x{ZONE_GRID[1]}",
        "weedy_zone_share": WEEDY_ZONE_SHARE,
        "crop_zone_share": CROP_ZONE_SHARE,
        "weedy": int(weedy.sum()),
        "crop_only": int(crop_only.sum()),
        "bare": int(bare.sum()),
        "clean": int((crop_only | bare).sum()),
        "not_counted": int((cells[:, 3] == 0).sum()),
        "thresholds": table,
        "best": dict(best, rule=rule),
    }


def _rounded(values, names):
    return {name: (None if np.isnan(v) else round(float(v), 4)) for name, v in zip(names, values)}


class Scores:
    """Per-image confusion matrices and zone cells, and the figures drawn from them."""

    def __init__(self, names, crop_class, weed_class, soil_class=0):
        self.names = list(names)
        self.crop_class = crop_class
        self.weed_class = weed_class
        self.soil_class = soil_class
        self.stems = []
        self.confusions = []
        self.cells = []
        self.limit_confusions = {}  # limits.py's figures, when add() is given the scores

    def add(self, stem, truth, predicted, scores=None):
        self.stems.append(stem)
        self.confusions.append(confusion_matrix(truth, predicted, len(self.names)))
        self.cells.append(zone_cells(truth, predicted, self.crop_class, self.weed_class))
        if scores is not None:
            for name, labels in (("true_outline", limits.true_outline(truth, scores, self.soil_class)),
                                 ("true_classes", limits.true_classes(truth, predicted, self.soil_class))):
                confusion = confusion_matrix(truth, labels, len(self.names))
                self.limit_confusions[name] = self.limit_confusions.get(name, 0) + confusion

    def per_image(self):
        rows = []
        for stem, confusion in zip(self.stems, self.confusions):
            iou = iou_per_class(confusion)
            rows.append({"image": stem, "iou": _rounded(iou, self.names),
                         "miou": None if np.all(np.isnan(iou)) else round(float(np.nanmean(iou)), 4)})
        return rows

    def summary(self):
        confusion = np.sum(self.confusions, axis=0)
        tp = np.diag(confusion).astype(float)
        iou = tp / np.maximum(confusion.sum(axis=1) + confusion.sum(axis=0) - tp, 1)
        accuracy = tp / np.maximum(confusion.sum(axis=1), 1)
        zones = zone_tradeoff(np.concatenate(self.cells))
        summary = {
            "iou": _rounded(iou, self.names),
            "miou": round(float(iou.mean()), 4),
            "pixel_accuracy": _rounded(accuracy, self.names),
            "mpa": round(float(accuracy.mean()), 4),
            "zones": zones,
            "images": len(self.stems),
            "per_image": self.per_image(),
            "intervals": self.intervals(zones["best"]["threshold"]),
        }
        if self.limit_confusions:
            summary["limits"] = {}
            for name, confusion in self.limit_confusions.items():
                limit_iou = iou_per_class(confusion)
                summary["limits"][name] = {"iou": _rounded(limit_iou, self.names),
                                           "miou": round(float(np.nanmean(limit_iou)), 4)}
        return summary

    def intervals(self, threshold, resamples=BOOTSTRAP_RESAMPLES, seed=0):
        """95 % percentile bootstrap over images of IoU per class, MIoU and the zone figures at
        threshold."""
        rng = np.random.default_rng(seed)
        confusions = np.stack(self.confusions)
        cells = np.stack(self.cells)
        ious, mious, zones = [], [], []
        for _ in range(resamples):
            pick = rng.integers(0, len(self.stems), len(self.stems))
            iou = iou_per_class(confusions[pick].sum(axis=0))
            ious.append(iou)
            mious.append(np.nan if np.all(np.isnan(iou)) else np.nanmean(iou))
            figures = zone_figures(cells[pick].reshape(-1, 4), threshold)
            zones.append([np.nan if figures[k] is None else figures[k] for k in ZONE_FIGURES])
        ious, zones = np.array(ious), np.array(zones)
        return {
            "method": f"95 % percentile bootstrap over the {len(self.stems)} images, {resamples} resamples",
            "iou": {name: _interval(ious[:, i]) for i, name in enumerate(self.names)},
            "miou": _interval(np.array(mious)),
            "zones": dict({k: _interval(zones[:, i]) for i, k in enumerate(ZONE_FIGURES)}, threshold=threshold),
        }


def _interval(samples):
    samples = samples[~np.isnan(samples)]
    if not samples.size:
        return None
    low, high = np.percentile(samples, [2.5, 97.5])
    return [round(float(low), 4), round(float(high), 4)]


def _add_prediction(scores, name, truth, net, bgr, spec, frame_mm_per_px, with_limits):
    planes = predict_scores(net, bgr, spec, frame_mm_per_px)
    scores.add(name, truth, planes.argmax(axis=0).astype(np.uint8), planes if with_limits else None)


def evaluate(net, spec, images, masks, stems, dataset_mm_per_px=None, with_limits=False):
    """All figures of net on the stems (see the module's docstring); with_limits adds
    limits.py's figures."""
    scores = Scores(spec["classes"], spec["crop_class"], spec["weed_class"], spec.get("soil_class", 0))
    for stem in stems:
        image, mask = load_pair(images, masks, stem, len(spec["classes"]))
        _add_prediction(scores, stem, mask, net, image, spec, dataset_mm_per_px, with_limits)
    return scores.summary()


def laid_frames(pairs, photo_mm_per_px, frame_mm_per_px, size):
    """(image, mask) pairs laid edge to edge, in order, into frames of size (W, H) as a camera of
    frame_mm_per_px sees the ground (io/sim/ground_mosaic.cpp): each photo resampled to that
    scale (area averaging, masks nearest), rows filled left to right, a photo cut where the
    frame ends; the last frame is filled from the first photos again. Unfilled pixels: 255."""
    factor = photo_mm_per_px / frame_mm_per_px
    width, height = size
    frames, i = [], 0
    while i < len(pairs):
        frame = np.zeros((height, width, 3), np.uint8)
        truth = np.full((height, width), IGNORE, np.uint8)
        y = 0
        while y < height:
            x, row = 0, 0
            while x < width:
                image, mask = pairs[i % len(pairs)]
                i += 1
                cell = (max(1, round(image.shape[1] * factor)), max(1, round(image.shape[0] * factor)))
                image = cv2.resize(image, cell, interpolation=cv2.INTER_AREA if factor < 1 else cv2.INTER_LINEAR)
                mask = cv2.resize(mask, cell, interpolation=cv2.INTER_NEAREST)
                w, h = min(cell[0], width - x), min(cell[1], height - y)
                frame[y:y + h, x:x + w] = image[:h, :w]
                truth[y:y + h, x:x + w] = mask[:h, :w]
                x += w
                row = max(row, h)
            y += row
        frames.append((frame, truth))
    return frames


def evaluate_laid(net, spec, images, masks, stems, photo_mm_per_px, frame_mm_per_px, size, with_limits=False):
    """The figures of evaluate() over frames of the stems laid as a camera sees them: each
    frame counts as one image (zones are the frame's, intervals are over frames)."""
    pairs = [load_pair(images, masks, stem, len(spec["classes"])) for stem in stems]
    scores = Scores(spec["classes"], spec["crop_class"], spec["weed_class"], spec.get("soil_class", 0))
    for n, (frame, truth) in enumerate(laid_frames(pairs, photo_mm_per_px, frame_mm_per_px, size)):
        _add_prediction(scores, f"frame {n}", truth, net, frame, spec, frame_mm_per_px, with_limits)
    return scores.summary()


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
    parser.add_argument("--dataset-mm-per-px", type=float, help="ground mm per pixel of the photos as stored")
    parser.add_argument("--lay-frames", metavar="WxH",
                        help="lay the photos edge to edge into frames of WxH as a camera of --frame-mm-per-px sees "
                             "the ground, and score the frames (needs --dataset-mm-per-px)")
    parser.add_argument("--frame-mm-per-px", type=float, help="the camera's ground mm per pixel for --lay-frames")
    parser.add_argument("--per-image", action="store_true", help="also print each image's IoU per class")
    parser.add_argument("--bench", action="store_true", help="also time one forward pass, one thread")
    parser.add_argument("--limits", action="store_true",
                        help="also score the model with the labels' plant outline and with the labels' classes "
                             "(limits.py: does the outline or the choice of class hold it back?)")
    args = parser.parse_args()
    with open(args.spec) as spec_file:
        spec = json.load(spec_file)["spec"]
    net = cv2.dnn.readNet(args.model)
    if args.lay_frames:
        try:
            size = tuple(int(v) for v in args.lay_frames.lower().split("x"))
            if len(size) != 2 or min(size) < 1:
                raise ValueError
        except ValueError:
            parser.error(f"--lay-frames '{args.lay_frames}': expected WxH, e.g. 1280x800")
        if not (args.dataset_mm_per_px and args.frame_mm_per_px):
            parser.error("--lay-frames needs --dataset-mm-per-px and --frame-mm-per-px (> 0)")
        result = evaluate_laid(net, spec, args.images, args.masks, read_list(args.list), args.dataset_mm_per_px,
                               args.frame_mm_per_px, size, args.limits)
    elif args.frame_mm_per_px:
        parser.error("--frame-mm-per-px is the camera's scale for --lay-frames; give --lay-frames WxH too")
    else:
        result = evaluate(net, spec, args.images, args.masks, read_list(args.list), args.dataset_mm_per_px,
                          args.limits)
    if not args.per_image:
        del result["per_image"]
    if args.bench:
        result["forward_ms_1_thread"] = median_forward_ms(net, spec)
    print(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
