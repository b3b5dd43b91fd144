# SPDX-License-Identifier: Apache-2.0
"""What train.py leaves for a person to judge and use: overlay pictures and the install.

Overlays (OUT/NAME-report/NN-STEM.png, the worst validation images first, ranked by the mean of
their crop and weed IoU): the photo with the model's classes tinted (green = crop, red = weed,
soil untinted), the labels' outlines drawn over it (white = crop, yellow = weed) and unlabelled
pixels darkened; the top line names the photo and its IoU per class.

Install (--install DIR): NAME.onnx and NAME.json copied into DIR and DIR/conf.d/50-model-NAME.toml
written, which sets [vision] weed_source = "dnn" and model = the absolute path of DIR/NAME.onnx;
the daemon reads DIR/weedspray.toml and then conf.d/*.toml in name order. The validation's best
zone threshold is noted there as a comment (spray.decision_threshold), not set.
"""

import json
import os
import shutil

import cv2
import numpy as np

from evaluate import IGNORE, load_pair, predict_labels

TINT_BGR = {"crop": (0, 200, 0), "weed": (0, 0, 255)}
OUTLINE_BGR = {"crop": (255, 255, 255), "weed": (0, 255, 255)}
TINT_ALPHA = 0.45
MAX_WIDTH = 960
LEGEND = ("tint = the model's classes (green crop, red weed, soil untinted); outline = the labels "
          "(white crop, yellow weed); darkened = unlabelled")


def ranking_score(row, spec):
    """Mean IoU of the image's crop and weed (those it has), else its MIoU; low = bad."""
    names = [spec["classes"][spec["crop_class"]], spec["classes"][spec["weed_class"]]]
    values = [row["iou"][n] for n in names if row["iou"].get(n) is not None]
    if values:
        return float(np.mean(values))
    return row["miou"] if row["miou"] is not None else 1.0


def worst_images(per_image, spec, count):
    return sorted(per_image, key=lambda row: ranking_score(row, spec))[:count]


def overlay(image, truth, predicted, spec, title):
    picture = image.astype(np.float32)
    for role in ("crop", "weed"):
        chosen = predicted == spec[f"{role}_class"]
        picture[chosen] = picture[chosen] * (1 - TINT_ALPHA) + np.array(TINT_BGR[role]) * TINT_ALPHA
    picture[truth == IGNORE] *= 0.45
    picture = np.clip(picture, 0, 255).astype(np.uint8)
    thickness = max(1, image.shape[1] // 480)
    for role in ("crop", "weed"):
        region = (truth == spec[f"{role}_class"]).astype(np.uint8)
        contours, _ = cv2.findContours(region, cv2.RETR_LIST, cv2.CHAIN_APPROX_SIMPLE)
        cv2.drawContours(picture, contours, -1, OUTLINE_BGR[role], thickness)
    if picture.shape[1] > MAX_WIDTH:
        height = round(picture.shape[0] * MAX_WIDTH / picture.shape[1])
        picture = cv2.resize(picture, (MAX_WIDTH, height), interpolation=cv2.INTER_AREA)
    band = np.zeros((28, picture.shape[1], 3), np.uint8)
    cv2.putText(band, title, (6, 19), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (255, 255, 255), 1, cv2.LINE_AA)
    return np.vstack([band, picture])


def write_overlays(net, spec, images, masks, rows, folder, frame_mm_per_px=None):
    """One overlay PNG per per_image row, in the rows' order; returns the file names."""
    os.makedirs(folder, exist_ok=True)
    written = []
    for rank, row in enumerate(rows, 1):
        image, truth = load_pair(images, masks, row["image"], len(spec["classes"]))
        predicted = predict_labels(net, image, spec, frame_mm_per_px)
        scores = " ".join(f"{n} {'-' if v is None else f'{v:.2f}'}" for n, v in row["iou"].items())
        name = f"{rank:02d}-{row['image']}.png"
        cv2.imwrite(os.path.join(folder, name), overlay(image, truth, predicted, spec, f"{row['image']}  IoU {scores}"))
        written.append(name)
    return written


def drop_in_text(name, onnx_path, best):
    note = ""
    if best:
        note = (f"# validation's best zone threshold: [spray] decision_threshold = {best['threshold']} "
                f"(recall {best['recall']}, crop-only zones left dry {best['crop_only_left_dry']})\n")
    return (f"# Written by tools/train/train.py --install: the weed model {name}; its spec, figures and\n"
            f"# licence are in {os.path.splitext(onnx_path)[0]}.json.\n{note}"
            f"[vision]\nweed_source = \"dnn\"\nmodel = {json.dumps(onnx_path)}\n")


def install(onnx_path, json_path, name, folder, best=None):
    """Copies the model into folder and writes its conf.d drop-in; returns the drop-in's path."""
    folder = os.path.abspath(folder)
    conf_d = os.path.join(folder, "conf.d")
    os.makedirs(conf_d, exist_ok=True)
    installed = os.path.join(folder, os.path.basename(onnx_path))
    for path in (onnx_path, json_path):
        target = os.path.join(folder, os.path.basename(path))
        if not os.path.exists(target) or not os.path.samefile(path, target):
            shutil.copyfile(path, target)
    drop_in = os.path.join(conf_d, f"50-model-{name}.toml")
    with open(drop_in, "w") as out:
        out.write(drop_in_text(name, installed, best))
    return drop_in
