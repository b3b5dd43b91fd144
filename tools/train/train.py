#!/usr/bin/python3
"""Trains a small crop/weed/soil segmentation network on CPU and exports it for OpenCV 4.6 DNN.

Any folder of images + same-named class-id PNG masks (0 soil, 1 crop, 2 weed by default) works:

    /usr/bin/python3 tools/train/train.py --images ../shared/data/peanut/images \
        --masks ../shared/data/peanut/masks --train-list tools/train/splits/peanut-train.txt \
        --val-list tools/train/splits/peanut-val.txt --out models --name weed-peanut \
        --epochs 48 --seed 9 --threads 1

Writes OUT/NAME.onnx and OUT/NAME.json (the spec the daemon needs, validation metrics through
OpenCV DNN, the training command, seed, versions, wall time). No downloaded weights; the run
length is a number of epochs, so a run is repeatable (as far as torch's CPU kernels are).
The augmentation is strong on purpose: the model has to work on other fields, crops and cameras
than the ones it saw (colour, brightness, gamma, hue, saturation, white balance, blur, noise,
scale, aspect, rotation, flips). The last epoch's weights are exported; the validation split is
only measured, never used to pick a checkpoint.
"""

import argparse
import json
import math
import os
import platform
import shlex
import sys
import time

import cv2
import numpy as np
import torch
import torch.nn.functional as F
import torchvision

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from evaluate import evaluate, load_pair, median_forward_ms, read_list, to_blob  # noqa: E402
from model import SegmentationNet  # noqa: E402
from onnx_export import export_onnx, load_opencv_net, max_abs_diff_vs_opencv  # noqa: E402

MEAN_RGB = (123.675, 116.28, 103.53)  # ImageNet means; scale 1/58 ~ 1/std
SCALE = 1.0 / 58.0
CACHE_FACTOR = 2  # training images are kept at twice the input size, so zooming in stays sharp


def parse_size(text):
    try:
        width, height = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"--input '{text}': expected WxH, e.g. 320x256")
    if width % 32 or height % 32 or width <= 0 or height <= 0:
        raise argparse.ArgumentTypeError(f"--input '{text}': width and height must be multiples of 32")
    return width, height


def parse_args():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--images", required=True, help="folder of images (jpg/png)")
    parser.add_argument("--masks", required=True, help="folder of STEM.png class-id masks")
    parser.add_argument("--train-list", required=True, help="image stems to train on, one per line")
    parser.add_argument("--val-list", required=True, help="image stems to measure on, one per line")
    parser.add_argument("--out", required=True, help="folder for NAME.onnx and NAME.json")
    parser.add_argument("--name", default="weed-model")
    parser.add_argument("--epochs", type=int, default=48)
    parser.add_argument("--seed", type=int, default=9)
    parser.add_argument("--input", type=parse_size, default=(320, 256), help="network input WxH")
    parser.add_argument("--crop", type=parse_size, default=(256, 192), help="training crop WxH (at input scale)")
    parser.add_argument("--batch", type=int, default=8)
    parser.add_argument("--lr", type=float, default=4e-3)
    parser.add_argument("--classes", default="soil,crop,weed", help="class names in class-id order")
    parser.add_argument("--soil-class", type=int, default=0)
    parser.add_argument("--crop-class", type=int, default=1)
    parser.add_argument("--weed-class", type=int, default=2)
    parser.add_argument("--class-weights", default="1,1.5,4", help="cross-entropy weight per class")
    parser.add_argument("--threads", type=int, default=2, help="torch threads (1 beats 2 on a busy machine)")
    parser.add_argument("--log-every", type=int, default=5, help="epochs between validation log lines")
    args = parser.parse_args()
    args.class_names = args.classes.split(",")
    args.weights = [float(v) for v in args.class_weights.split(",")]
    if len(args.weights) != len(args.class_names):
        parser.error(f"--class-weights has {len(args.weights)} values for {len(args.class_names)} --classes")
    for key in ("soil_class", "crop_class", "weed_class"):
        if not 0 <= getattr(args, key) < len(args.class_names):
            parser.error(f"--{key.replace('_', '-')} {getattr(args, key)}: not a class id of --classes")
    return args


def load_cache(args, stems):
    """Images and masks resized to CACHE_FACTOR x the input size (squeezed as at inference)."""
    width, height = args.input[0] * CACHE_FACTOR, args.input[1] * CACHE_FACTOR
    images, masks = [], []
    for stem in stems:
        image, mask = load_pair(args.images, args.masks, stem, len(args.class_names))
        images.append(cv2.resize(image, (width, height), interpolation=cv2.INTER_AREA))
        masks.append(cv2.resize(mask, (width, height), interpolation=cv2.INTER_NEAREST))
    return images, masks


def random_geometry(rng, image, mask, out_size):
    """A crop of out_size at a random zoom (0.6-1.7 x the inference scale), aspect, rotation,
    flip and position."""
    out_w, out_h = out_size
    cache_h, cache_w = image.shape[:2]
    zoom = math.exp(rng.uniform(math.log(0.6), math.log(1.7))) / CACHE_FACTOR
    aspect = math.exp(rng.uniform(-0.15, 0.15))
    sx, sy = zoom * aspect, zoom / aspect
    angle = rng.uniform(-math.pi, math.pi) if rng.random() < 0.7 else 0.0
    cos, sin = math.cos(angle), math.sin(angle)
    # Output = A * (source - centre) + output centre, A = rotation * scale * flips.
    linear = np.array([[cos, -sin], [sin, cos]]) @ np.diag([sx, sy])
    if rng.random() < 0.5:
        linear = linear @ np.diag([-1.0, 1.0])
    if rng.random() < 0.5:
        linear = linear @ np.diag([1.0, -1.0])
    centre = np.array([rng.uniform(0, cache_w), rng.uniform(0, cache_h)])
    offset = np.array([out_w / 2, out_h / 2]) - linear @ centre
    matrix = np.hstack([linear, offset[:, None]])
    warped = cv2.warpAffine(image, matrix, out_size, flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT_101)
    warped_mask = cv2.warpAffine(mask, matrix, out_size, flags=cv2.INTER_NEAREST, borderMode=cv2.BORDER_REFLECT_101)
    return warped, warped_mask


def random_photometry(rng, bgr):
    """Colour, light and camera changes another field or camera may bring; float RGB 0-255 out."""
    image = bgr.astype(np.float32) / 255.0
    hsv = cv2.cvtColor(image, cv2.COLOR_BGR2HSV)
    hsv[..., 0] = (hsv[..., 0] + rng.uniform(-15, 15)) % 360.0
    hsv[..., 1] *= rng.uniform(0.55, 1.45)
    image = cv2.cvtColor(np.clip(hsv, 0, [360, 1, 1]).astype(np.float32), cv2.COLOR_HSV2BGR)
    image *= rng.uniform(0.85, 1.15, size=3).astype(np.float32)  # white balance
    image *= rng.uniform(0.55, 1.5)  # exposure
    mean = image.mean()
    image = (image - mean) * rng.uniform(0.7, 1.3) + mean  # contrast
    image = np.clip(image, 0, 1) ** rng.uniform(0.7, 1.45)  # gamma
    if rng.random() < 0.4:
        image = cv2.GaussianBlur(image, (0, 0), rng.uniform(0.4, 1.6))
    if rng.random() < 0.5:
        image += rng.normal(0, rng.uniform(0.005, 0.04), image.shape).astype(np.float32)
    image = np.clip(image, 0, 1) * 255.0
    return image[..., ::-1]  # RGB


def batches(rng, cache, args):
    images, masks = cache
    order = rng.permutation(len(images))
    for start in range(0, len(order) - args.batch + 1, args.batch):
        inputs, targets = [], []
        for i in order[start : start + args.batch]:
            image, mask = random_geometry(rng, images[i], masks[i], args.crop)
            rgb = random_photometry(rng, image)
            inputs.append(((rgb - np.array(MEAN_RGB, np.float32)) * SCALE).transpose(2, 0, 1))
            targets.append(mask)
        yield torch.from_numpy(np.stack(inputs).astype(np.float32)), torch.from_numpy(np.stack(targets).astype(np.int64))


def loss_fn(logits, target, class_weights):
    cross_entropy = F.cross_entropy(logits, target, weight=class_weights)
    probabilities = logits.softmax(dim=1)
    one_hot = F.one_hot(target, logits.shape[1]).permute(0, 3, 1, 2).float()
    intersection = (probabilities * one_hot).sum(dim=(0, 2, 3))
    total = probabilities.sum(dim=(0, 2, 3)) + one_hot.sum(dim=(0, 2, 3))
    dice = 1.0 - ((2 * intersection + 1.0) / (total + 1.0)).mean()
    return cross_entropy + dice


def learning_rate(step, total, peak):
    warmup = max(1, total // 30)
    if step < warmup:
        return peak * (step + 1) / warmup
    return 0.5 * peak * (1 + math.cos(math.pi * (step - warmup) / max(1, total - warmup)))


def quick_val_miou(model, args, val_pairs):
    """MIoU at the network's resolution with torch (progress log only)."""
    spec = model_spec(args)
    classes = len(args.class_names)
    confusion = np.zeros((classes, classes), np.int64)
    model.eval()
    with torch.no_grad():
        for image, mask in val_pairs:
            labels = model(torch.from_numpy(to_blob(image, spec)))[0].argmax(0).numpy()
            small = cv2.resize(mask, args.input, interpolation=cv2.INTER_NEAREST)
            confusion += np.bincount(small.ravel().astype(np.int64) * classes + labels.ravel(),
                                     minlength=classes**2).reshape(classes, classes)
    model.train()
    tp = np.diag(confusion)
    iou = tp / np.maximum(confusion.sum(0) + confusion.sum(1) - tp, 1)
    return iou


def model_spec(args):
    return {
        "input_width": args.input[0],
        "input_height": args.input[1],
        "mean_rgb": list(MEAN_RGB),
        "scale": SCALE,
        "rgb": True,
        "resize": "whole frame to input size, INTER_AREA, aspect not kept",
        "classes": args.class_names,
        "soil_class": args.soil_class,
        "crop_class": args.crop_class,
        "weed_class": args.weed_class,
        "input_name": "input",
        "output": "logits, 1 x classes x input_height x input_width (argmax = class id)",
    }


def main():
    args = parse_args()
    command = " ".join(["/usr/bin/python3", "tools/train/train.py"] + [shlex.quote(a) for a in sys.argv[1:]])
    torch.set_num_threads(args.threads)
    cv2.setNumThreads(1)
    torch.manual_seed(args.seed)
    torch.use_deterministic_algorithms(True, warn_only=True)
    rng = np.random.default_rng(args.seed)
    train_stems, val_stems = read_list(args.train_list), read_list(args.val_list)
    overlap = set(train_stems) & set(val_stems)
    if overlap:
        raise SystemExit(f"--train-list and --val-list share {len(overlap)} images, e.g. {sorted(overlap)[0]}")
    cache = load_cache(args, train_stems)
    val_pairs = [load_pair(args.images, args.masks, s, len(args.class_names)) for s in val_stems]

    model = SegmentationNet(len(args.class_names))
    optimiser = torch.optim.AdamW(model.parameters(), lr=args.lr, weight_decay=1e-4)
    class_weights = torch.tensor(args.weights)
    steps_per_epoch = len(train_stems) // args.batch
    total = steps_per_epoch * args.epochs
    print(f"{len(train_stems)} train / {len(val_stems)} val images, {total} iterations, "
          f"{sum(p.numel() for p in model.parameters())} parameters", flush=True)
    started = time.time()
    step = 0
    model.train()
    for epoch in range(1, args.epochs + 1):
        running = 0.0
        for inputs, targets in batches(rng, cache, args):
            for group in optimiser.param_groups:
                group["lr"] = learning_rate(step, total, args.lr)
            loss = loss_fn(model(inputs), targets, class_weights)
            optimiser.zero_grad()
            loss.backward()
            optimiser.step()
            running += loss.item()
            step += 1
        line = f"epoch {epoch}/{args.epochs} loss {running / steps_per_epoch:.4f} {time.time() - started:.0f} s"
        if epoch % args.log_every == 0 or epoch == args.epochs:
            iou = quick_val_miou(model, args, val_pairs)
            line += " val IoU " + " ".join(f"{n} {v:.3f}" for n, v in zip(args.class_names, iou))
            line += f" MIoU {iou.mean():.3f}"
        print(line, flush=True)
    wall_s = time.time() - started

    model.eval()
    os.makedirs(args.out, exist_ok=True)
    onnx_path = os.path.join(args.out, args.name + ".onnx")
    export_onnx(model, onnx_path, *args.input)
    spec = model_spec(args)
    check = [torch.from_numpy(to_blob(image, spec)) for image, _ in val_pairs[:4]]
    diff = max_abs_diff_vs_opencv(model, onnx_path, check)
    if diff > 1e-3:
        raise SystemExit(f"{onnx_path}: OpenCV DNN output differs from torch by {diff}")
    net = load_opencv_net(onnx_path)
    report = {
        "model": os.path.basename(onnx_path),
        "spec": spec,
        "validation": evaluate(net, spec, args.images, args.masks, val_stems),
        "training_set": evaluate(net, spec, args.images, args.masks, train_stems),
        "export": {"onnx_bytes": os.path.getsize(onnx_path), "opset": 11,
                   "opencv_vs_torch_max_abs_diff": diff, "parameters": sum(p.numel() for p in model.parameters())},
        "inference": {"forward_ms_1_thread": median_forward_ms(net, spec), "opencv": cv2.__version__,
                      "machine": f"{platform.machine()}, {os.cpu_count()} cores (shared with other work)"},
        "training": {
            "command": command,
            "seed": args.seed,
            "epochs": args.epochs,
            "iterations": total,
            "batch": args.batch,
            "crop": list(args.crop),
            "lr": args.lr,
            "class_weights": args.weights,
            "train_list": args.train_list,
            "val_list": args.val_list,
            "train_images": len(train_stems),
            "val_images": len(val_stems),
            "threads": args.threads,
            "wall_s": round(wall_s, 1),
            "torch": torch.__version__,
            "torchvision": torchvision.__version__,
            "opencv": cv2.__version__,
            "pretrained_weights": None,
        },
    }
    json_path = os.path.join(args.out, args.name + ".json")
    with open(json_path, "w") as out:
        json.dump(report, out, indent=2)
        out.write("\n")
    v = report["validation"]
    print(f"{onnx_path}: val IoU {v['iou']} MIoU {v['miou']} MPA {v['mpa']}; zones best {v['zones']['best']}; "
          f"forward {report['inference']['forward_ms_1_thread']} ms; OpenCV-torch diff {diff:.2e}", flush=True)


if __name__ == "__main__":
    main()
