#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""Trains a small crop/weed/soil segmentation network on CPU and exports it for OpenCV 4.6 DNN.

Made for a field's own model from 25-40 labelled photos on a 2-core CPU in under 30 minutes:
label the photos (tools/train/import_labels.py turns CVAT, LabelMe, COCO or palette exports
into masks), split them (split.py keeps near-duplicate photos on one side), then fine-tune the
plant/soil base network (train_base.py; the default --base) for your classes:

    /usr/bin/python3 tools/train/split.py --images ~/carrots/images --masks ~/carrots/masks \
        --val-fraction 0.25 --seed 9 --train-out ~/carrots/train.txt --val-out ~/carrots/val.txt
    /usr/bin/python3 tools/train/train.py --images ~/carrots/images --masks ~/carrots/masks \
        --train-list ~/carrots/train.txt --val-list ~/carrots/val.txt --out ~/carrots/model \
        --name weed-carrot --dataset-mm-per-px 0.4 --data-licence "own photos, Farm X" \
        --install /etc/weedspray

Masks: STEM.png beside each STEM.jpg in --masks, one class id per pixel (0 soil, 1 crop, 2 weed
by default: --classes), 255 = unlabelled (no loss, no figure). The validation list is only
measured, never used to pick anything; the last step's weights are exported.

Training: --steps optimiser steps (default 2500: 9 min at the ~4.8 steps/s of the project's
2-core x86 machine when idle; a laptop CPU or a busy machine is slower, so each progress line
shows steps/s and the time left, and --steps trades time for accuracy), or --epochs (converted
to epochs x max(1, photos // batch) steps). Each step draws --batch crops from the training
photos with replacement, so a handful of photos works.
Loss: class-weighted cross-entropy + Dice over the labelled pixels; --class-weights auto (the
default) weighs each class by sqrt(share of the most frequent class / its share), clipped to
[1, 20], and prints the weights. Augmentation aims at other fields and cameras: zoom, aspect,
rotation, flips, hue, saturation, white balance, exposure, contrast, gamma, blur, noise
(sampling.py). A crop under 5 % of the training photos' labelled pixels is also pasted: half
the training crops get the crop pixels of another crop laid over them (--paste-crop: auto, or a
probability), so a rare crop is seen on more ground.

Ground scale: --dataset-mm-per-px X is the ground size of one pixel of the photos as stored;
--target-mm-per-px Y the ground size of one pixel at the network input (default X x photo
width / input width: the photo squeezed to --input). Every photo is resampled to Y and crops are
drawn at Y times a zoom in --zoom (0.7-1.4); spec.ground_mm_per_px = Y lets the daemon resample
each camera's frames to the scale the model learnt. Without X the scale is unknown:
ground_mm_per_px is null and the daemon squeezes frames to the input size whatever their scale.

--base PATH.pt starts from a checkpoint's encoder and decoder with a new class head (kept when
the class names are the same, as when going on from a train.py NAME.pt). By default (--base auto)
that is models/base-plant-soil.pt, the plant/soil network train_base.py learnt from all shared
photo sets: its training data and their licences are recorded in NAME.json and pass to the
model. --base none trains from scratch.

A class whose share of the labelled pixels differs more than 2x between the training and the
validation photos is warned of before training: such validation photos judge the model on
ground unlike what it learns from (a model learnt on photos that are mostly weed calls more weed).

Writes into --out:
- NAME.onnx, checked against torch through OpenCV DNN, and NAME.pt (a checkpoint --base takes);
- NAME.json: spec (what the daemon feeds the network, classes, ground_mm_per_px, stride,
  input_channels), licence, training_data (each photo folder with its count, licence and
  attribution, from datasets.json or --data-licence/--data-attribution; a base's data too),
  validation (IoU per class, MIoU, MPA, zones, per_image, intervals: evaluate.py), training_set,
  report, export, inference, training (command, seed, steps, class weights, the class shares of
  the training and the validation photos, crop pasting, scales, versions);
- NAME-report/: the --report-worst validation photos with the lowest crop/weed IoU as overlays
  (report.py).
--install DIR copies NAME.onnx and NAME.json into DIR and writes DIR/conf.d/50-model-NAME.toml.
"""

import argparse
import json
import os
import platform
import re
import shlex
import statistics
import sys
import time

import cv2
import numpy as np
import torch
import torchvision

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from datasets import model_licence, training_data_entry  # noqa: E402
from evaluate import evaluate, find_image, load_pair, median_forward_ms, read_list, to_blob  # noqa: E402
from loss import auto_class_weights, parse_class_weights  # noqa: E402
from model import SegmentationNet, load_checkpoint_into, read_checkpoint, save_checkpoint, stride  # noqa: E402
from onnx_export import OPSET, export_onnx, load_opencv_net, max_abs_diff_vs_opencv  # noqa: E402
from report import LEGEND, install, worst_images, write_overlays  # noqa: E402
from sampling import MEAN_RGB, SCALE, SHIFT_FACTOR, Sampler, ScaledPhoto, class_frequencies, share_shifts  # noqa: E402
from trainer import format_seconds, quick_iou, train_steps  # noqa: E402

DEFAULT_STEPS = 2500
DEFAULT_ZOOM = (0.7, 1.4)
# --paste-crop auto: crops get another crop's crop pixels this often when the crop covers less
# than PASTE_BELOW_SHARE of the training photos' labelled pixels.
PASTE_PROBABILITY = 0.5
PASTE_BELOW_SHARE = 0.05
STRIDE = 32
WIDTH = 0.5
BASE_SCALE_MISMATCH = 1.4
NAME_PATTERN = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]*$")
# The plant/soil network train_base.py learnt from every shared photo set, in the checkout's models/.
DEFAULT_BASE = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))),
                            "models", "base-plant-soil.pt")


def parse_size(text):
    try:
        width, height = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"'{text}': expected WxH, e.g. 320x256")
    if width % STRIDE or height % STRIDE or width <= 0 or height <= 0:
        raise argparse.ArgumentTypeError(f"'{text}': width and height must be multiples of {STRIDE}")
    return width, height


def parse_range(text):
    try:
        low, high = (float(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"'{text}': expected MIN,MAX, e.g. 0.7,1.4")
    if not 0 < low <= high:
        raise argparse.ArgumentTypeError(f"'{text}': need 0 < MIN <= MAX")
    return low, high


def parse_paste(text):
    if text.strip().lower() == "auto":
        return None
    try:
        value = float(text)
    except ValueError:
        value = -1.0
    if not 0 <= value <= 1:
        raise argparse.ArgumentTypeError(f"'{text}': expected 'auto' or a probability from 0 to 1")
    return value


def positive(kind):
    def check(text):
        value = kind(text)
        if value <= 0:
            raise argparse.ArgumentTypeError(f"{text}: must be > 0")
        return value

    return check


def build_parser():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--images", required=True, help="folder of images (jpg/png)")
    parser.add_argument("--masks", required=True, help="folder of STEM.png class-id masks (255 = unlabelled)")
    parser.add_argument("--train-list", required=True, help="image stems to train on, one per line")
    parser.add_argument("--val-list", required=True, help="image stems to measure on, one per line")
    parser.add_argument("--out", required=True, help="folder for NAME.onnx, NAME.json, NAME.pt, NAME-report/")
    parser.add_argument("--name", default="weed-model", help="model name (letters, digits, . _ -)")
    length = parser.add_mutually_exclusive_group()
    length.add_argument("--steps", type=positive(int), help=f"optimiser steps (default {DEFAULT_STEPS})")
    length.add_argument("--epochs", type=positive(int), help="passes over the training photos, converted to steps")
    parser.add_argument("--seed", type=int, default=9)
    parser.add_argument("--input", type=parse_size, default=(320, 256), help="network input WxH")
    parser.add_argument("--crop", type=parse_size, default=(256, 192), help="training crop WxH (at the target scale)")
    parser.add_argument("--detail", type=int, choices=(1, 2, 4), default=1,
                        help="input K times finer than the network's body sees it; classes come out at 1/K of the "
                             "input's size (sides then multiples of 32 K)")
    parser.add_argument("--batch", type=positive(int), default=8)
    parser.add_argument("--lr", type=positive(float), default=4e-3)
    parser.add_argument("--classes", default="soil,crop,weed", help="class names in class-id order")
    parser.add_argument("--soil-class", type=int, default=0)
    parser.add_argument("--crop-class", type=int, default=1)
    parser.add_argument("--weed-class", type=int, default=2)
    parser.add_argument("--class-weights", default="auto", help="'auto' or one cross-entropy weight per class")
    parser.add_argument("--paste-crop", type=parse_paste, default=None, metavar="auto|P",
                        help="probability that a training crop gets the crop pixels of another crop, from any "
                             f"training photo with crop, laid over it; auto (the default): {PASTE_PROBABILITY:g} "
                             f"when the crop covers under "
                             f"{PASTE_BELOW_SHARE * 100:g} per cent of the training photos' labelled pixels, else 0")
    parser.add_argument("--dataset-mm-per-px", type=positive(float), help="ground mm per pixel of the photos as stored")
    parser.add_argument("--target-mm-per-px", type=positive(float),
                        help="ground mm per pixel at the network input (default: the photo squeezed to --input)")
    parser.add_argument("--zoom", type=parse_range, default=DEFAULT_ZOOM, help="random zoom around the target scale")
    parser.add_argument("--base", default="auto",
                        help="checkpoint to start from (train_base.py's NAME.pt, or a train.py NAME.pt); 'auto' (the "
                             "default): the project's plant/soil base network, models/base-plant-soil.pt of this checkout; "
                             "'none': from scratch")
    parser.add_argument("--threads", type=positive(int), default=2,
                        help="torch threads: the machine's cores when it trains alone; 1 when another job shares them")
    parser.add_argument("--log-every", type=positive(int), default=25, help="steps between progress lines")
    parser.add_argument("--val-every", type=positive(int), default=300, help="steps between quick validation figures")
    parser.add_argument("--report-worst", type=int, default=6, help="validation photos drawn as overlays")
    parser.add_argument("--data-licence", help="licence of --images when datasets.json does not know the folder")
    parser.add_argument("--data-attribution", help="attribution of --images (who took and labelled them)")
    parser.add_argument("--install", metavar="DIR",
                        help="copy the model into DIR and write DIR/conf.d/50-model-NAME.toml")
    return parser


def parse_args(argv=None):
    parser = build_parser()
    args = parser.parse_args(argv)
    args.class_names = args.classes.split(",")
    try:
        args.weights = parse_class_weights(args.class_weights, len(args.class_names))
    except ValueError as error:
        parser.error(str(error))
    for key in ("soil_class", "crop_class", "weed_class"):
        if not 0 <= getattr(args, key) < len(args.class_names):
            parser.error(f"--{key.replace('_', '-')} {getattr(args, key)}: not a class id of --classes")
    if not NAME_PATTERN.match(args.name):
        parser.error(f"--name '{args.name}': use letters, digits, '.', '_' and '-'")
    for option, (width, height) in (("--input", args.input), ("--crop", args.crop)):
        if width % stride(args.detail) or height % stride(args.detail):
            parser.error(f"{option} {width}x{height}: with --detail {args.detail} the sides must be multiples of "
                         f"{stride(args.detail)}")
    args.base = resolve_base(args.base)
    if args.target_mm_per_px and not args.dataset_mm_per_px:
        parser.error("--target-mm-per-px needs --dataset-mm-per-px (the photos' own ground scale)")
    return args


def resolve_base(text):
    """--base as given -> the checkpoint's path, or None for a network trained from scratch."""
    if text.strip().lower() == "none":
        return None
    if text.strip().lower() == "auto":
        if not os.path.exists(DEFAULT_BASE):
            print(f"note: no {DEFAULT_BASE} (the plant/soil base network): training from scratch", flush=True)
            return None
        return DEFAULT_BASE
    return text


def photo_width(images, stem):
    path = find_image(images, stem)
    try:
        from PIL import Image

        with Image.open(path) as image:
            return image.size[0]
    except ImportError:
        return cv2.imread(path, cv2.IMREAD_COLOR).shape[1]


def ground_scale(args, stems):
    """(photo mm/px, target mm/px, ground_mm_per_px for the spec or None); with the scale
    unknown, 'mm' is a photo pixel and the target squeezes the photo to the input width."""
    width = statistics.median(photo_width(args.images, s) for s in stems)
    if args.dataset_mm_per_px:
        target = args.target_mm_per_px or args.dataset_mm_per_px * width / args.input[0]
        return args.dataset_mm_per_px, target, target
    return 1.0, width / args.input[0], None


def shares_text(names, shares):
    return ", ".join(f"{n} {f:.1%}" for n, f in zip(names, shares))


def shares_record(names, shares):
    return {n: round(float(f), 4) for n, f in zip(names, shares)}


def warn_of_share_shifts(names, training, validation):
    print("validation class shares " + shares_text(names, validation), flush=True)
    for name, a, b in share_shifts(names, training, validation):
        print(f"warning: class '{name}' covers {a:.1%} of the training photos' labelled pixels but {b:.1%} of the "
              f"validation photos' (more than {SHIFT_FACTOR:g}x apart): the model is judged on photos unlike "
              f"those it learns from; label photos of the growth stage and ground it will meet "
              f"(docs/vision.md, 'Photos unlike the ones it must judge')", flush=True)


def load_photos(args, stems, photo_mm, target_mm):
    photos = []
    for stem in stems:
        image, mask = load_pair(args.images, args.masks, stem, len(args.class_names))
        photos.append(ScaledPhoto(image, mask, photo_mm, target_mm))
    return photos


def resolve_class_weights(args, photos):
    frequencies = class_frequencies([p.mask for p in photos], len(args.class_names))
    if args.weights is not None:
        return args.weights, "given", frequencies
    for name, share in zip(args.class_names, frequencies):
        if share == 0:
            print(f"warning: class '{name}' has no labelled pixel in the training photos", flush=True)
    return auto_class_weights(frequencies), "auto: sqrt(top share / share), clipped to [1, 20]", frequencies


def resolve_paste(args, frequencies):
    """(probability, how it was set) of pasting crop pixels into a training crop."""
    share = frequencies[args.crop_class]
    if args.paste_crop is not None:
        return args.paste_crop, "given"
    if 0 < share < PASTE_BELOW_SHARE:
        print(f"the crop covers {share:.1%} of the training photos' labelled pixels (under {PASTE_BELOW_SHARE:.0%}): "
              f"{PASTE_PROBABILITY:g} of the training crops get another crop's crop pixels (--paste-crop 0 for none)",
              flush=True)
        return PASTE_PROBABILITY, f"auto: crop share under {PASTE_BELOW_SHARE:g}"
    return 0.0, f"auto: crop share {PASTE_BELOW_SHARE:g} or more"


def build_model(args, target_mm):
    """The network, fresh or from --base; and what the base brings ({} without one)."""
    model = SegmentationNet(len(args.class_names), width=WIDTH, detail=args.detail)
    if not args.base:
        return model, {}
    try:
        checkpoint = read_checkpoint(args.base)
        kept = load_checkpoint_into(model, checkpoint, args.class_names)
    except ValueError as error:
        raise SystemExit(f"--base {error}")
    meta = checkpoint.get("meta", {})
    base_mm = meta.get("ground_mm_per_px")
    print(f"--base {args.base}: classes {checkpoint['classes']} -> {args.class_names}, "
          f"class head {'kept' if kept else 'new'}, learnt at {base_mm} mm/px; the model carries its data's "
          f"licences: {meta.get('licence', 'not recorded')}", flush=True)
    body_mm = target_mm * args.detail if target_mm else None
    if base_mm and body_mm and max(base_mm / body_mm, body_mm / base_mm) > BASE_SCALE_MISMATCH:
        print(f"warning: the base learnt at {base_mm} mm/px, this model's body sees {body_mm:.3g} mm/px "
              f"(more than {BASE_SCALE_MISMATCH}x apart): its features fit this scale less; "
              f"--target-mm-per-px {base_mm / args.detail:g} trains at the base's scale", flush=True)
    elif base_mm and not target_mm:
        print(f"note: the base learnt at {base_mm} mm/px, but these photos' scale is unknown: "
              f"--dataset-mm-per-px lets them be resampled to a scale of your choice", flush=True)
    return model, {"path": os.path.abspath(args.base), "classes": checkpoint["classes"], "ground_mm_per_px": base_mm,
                   "training_data": meta.get("training_data", []), "head": "kept" if kept else "new"}


def model_spec(args, ground_mm):
    if ground_mm:
        note = f"one network input pixel covers {ground_mm:.4g} mm of ground"
    else:
        note = "unknown: trained without --dataset-mm-per-px"
    return {
        "input_width": args.input[0],
        "input_height": args.input[1],
        "stride": stride(args.detail),
        "input_channels": 3,
        "mean_rgb": list(MEAN_RGB),
        "scale": SCALE,
        "rgb": True,
        "resize": "whole frame, area averaging (by a whole factor dividing each side, then the rest, bilinear when it "
                  "shrinks by less than half): to ground_mm_per_px per pixel when known (sides rounded to the stride), "
                  "else to the input size (aspect not kept)",
        "classes": args.class_names,
        "soil_class": args.soil_class,
        "crop_class": args.crop_class,
        "weed_class": args.weed_class,
        "input_name": "input",
        "output": ("logits, 1 x classes x input_height x input_width (argmax = class id)" if args.detail == 1 else
                   f"logits, 1 x classes x input_height/{args.detail} x input_width/{args.detail} (argmax = class id)"),
        "ground_mm_per_px": round(ground_mm, 4) if ground_mm else None,
        "ground_scale_note": note,
    }


def training_data(args, count, base):
    records = [training_data_entry(args.images, count, args.data_licence, args.data_attribution)]
    for record in base.get("training_data", []):
        records.append(dict(record, via=f"base {os.path.basename(base['path'])}"))
    return records


def command_line(argv):
    return " ".join(["/usr/bin/python3", "tools/train/train.py"] + [shlex.quote(a) for a in argv])


def export_and_check(model, args, onnx_path, spec, val_images):
    model.eval()
    export_onnx(model, onnx_path, *args.input)
    check = [torch.from_numpy(to_blob(image, spec)) for image in val_images[:4]]
    diff = max_abs_diff_vs_opencv(model, onnx_path, check)
    if diff > 1e-3:
        raise SystemExit(f"{onnx_path}: OpenCV DNN output differs from torch by {diff}")
    return diff


def announce_scale(args, photo_mm, target_mm, ground_mm):
    if ground_mm:
        print(f"ground scale: photos {photo_mm:.4g} mm/px, network input {target_mm:.4g} mm/px, "
              f"zoom {args.zoom[0]}-{args.zoom[1]}x around it", flush=True)
    else:
        print(f"--dataset-mm-per-px not given: the ground scale is unknown; photos are scaled to the input width "
              f"({args.input[0]} px) as at inference, spec.ground_mm_per_px = null, and the daemon will squeeze "
              f"each frame to {args.input[0]}x{args.input[1]} whatever its camera's scale", flush=True)


def read_lists(args):
    train_stems, val_stems = read_list(args.train_list), read_list(args.val_list)
    overlap = set(train_stems) & set(val_stems)
    if overlap:
        raise SystemExit(f"--train-list and --val-list share {len(overlap)} images, e.g. {sorted(overlap)[0]}")
    return train_stems, val_stems


def seed_everything(args):
    torch.set_num_threads(args.threads)
    cv2.setNumThreads(1)
    torch.manual_seed(args.seed)
    torch.use_deterministic_algorithms(True, warn_only=True)
    return np.random.default_rng(args.seed)


def step_count(args, photos):
    if args.steps:
        return args.steps
    return args.epochs * max(1, photos // args.batch) if args.epochs else DEFAULT_STEPS


def validation_line(args, spec, val_pairs):
    """validate(model) for the progress lines: torch IoU per class on the validation photos."""
    samples = [(image, mask, args.dataset_mm_per_px) for image, mask in val_pairs]

    def validate(model):
        iou = quick_iou(model, samples, spec)
        return "val IoU " + " ".join(f"{n} {v:.3f}" for n, v in zip(args.class_names, iou)) + f" MIoU {iou.mean():.3f}"

    return validate


def measure(args, model, spec, val_pairs, stems):
    """Exports NAME.onnx and measures it through OpenCV DNN: (onnx path, net, figures)."""
    os.makedirs(args.out, exist_ok=True)
    onnx_path = os.path.join(args.out, args.name + ".onnx")
    diff = export_and_check(model, args, onnx_path, spec, [image for image, _ in val_pairs])
    net = load_opencv_net(onnx_path)
    train_stems, val_stems = stems
    training_set = evaluate(net, spec, args.images, args.masks, train_stems, args.dataset_mm_per_px)
    for key in ("per_image", "intervals"):
        del training_set[key]
    figures = {
        "validation": evaluate(net, spec, args.images, args.masks, val_stems, args.dataset_mm_per_px, with_limits=True),
        "training_set": training_set,
        "export": {"onnx_bytes": os.path.getsize(onnx_path), "opset": OPSET, "opencv_vs_torch_max_abs_diff": diff,
                   "parameters": sum(p.numel() for p in model.parameters())},
        "inference": {"forward_ms_1_thread": median_forward_ms(net, spec), "opencv": cv2.__version__,
                      "machine": f"{platform.machine()}, {os.cpu_count()} cores (shared with other work)"},
    }
    return onnx_path, net, figures


def overlays(args, net, spec, validation):
    folder = os.path.join(args.out, args.name + "-report")
    worst = worst_images(validation["per_image"], spec, max(0, args.report_worst))
    pictures = write_overlays(net, spec, args.images, args.masks, worst, folder, args.dataset_mm_per_px)
    return {"folder": os.path.basename(folder), "worst": pictures, "legend": LEGEND}


def training_record(args, argv, run, setup):
    """The JSON's training object: how to repeat the run and what it used."""
    return {
        "command": command_line(argv),
        "seed": args.seed,
        "steps": setup["steps"],
        "epochs": args.epochs,
        "iterations": setup["steps"],
        "batch": args.batch,
        "crop": list(args.crop),
        "detail": args.detail,
        "lr": args.lr,
        "class_weights": setup["weights"],
        "class_weights_method": setup["weights_method"],
        "class_shares": shares_record(args.class_names, setup["frequencies"]),
        "paste_crop": {"probability": setup["paste"][0], "method": setup["paste"][1]},
        "validation_class_shares": shares_record(args.class_names, setup["val_frequencies"]),
        "dataset_mm_per_px": args.dataset_mm_per_px,
        "target_mm_per_px": round(setup["target_mm"], 4) if setup["ground_mm"] else None,
        "zoom": list(args.zoom),
        "train_list": args.train_list,
        "val_list": args.val_list,
        "train_images": setup["train_images"],
        "val_images": setup["val_images"],
        "threads": args.threads,
        "steps_per_s": run["steps_per_s"],
        "wall_s": run["wall_s"],
        "torch": torch.__version__,
        "torchvision": torchvision.__version__,
        "opencv": cv2.__version__,
        "pretrained_weights": setup["base"].get("path"),
        "base": setup["base"] or None,
    }


def write_json(path, document):
    with open(path, "w") as out:
        json.dump(document, out, indent=2)
        out.write("\n")


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    args = parse_args(argv)
    started = time.time()
    rng = seed_everything(args)
    train_stems, val_stems = read_lists(args)
    photo_mm, target_mm, ground_mm = ground_scale(args, train_stems)
    announce_scale(args, photo_mm, target_mm, ground_mm)
    photos = load_photos(args, train_stems, photo_mm, target_mm)
    weights, weights_method, frequencies = resolve_class_weights(args, photos)
    print("class shares " + shares_text(args.class_names, frequencies) + "; weights "
          + ", ".join(f"{n} {w:g}" for n, w in zip(args.class_names, weights)), flush=True)
    val_pairs = [load_pair(args.images, args.masks, s, len(args.class_names)) for s in val_stems]
    val_frequencies = class_frequencies([mask for _, mask in val_pairs], len(args.class_names))
    warn_of_share_shifts(args.class_names, frequencies, val_frequencies)
    paste = resolve_paste(args, frequencies)
    spec = model_spec(args, ground_mm)
    model, base = build_model(args, ground_mm)
    steps = step_count(args, len(train_stems))
    print(f"{len(train_stems)} train / {len(val_stems)} val photos, {steps} steps of {args.batch} crops "
          f"{args.crop[0]}x{args.crop[1]}, {sum(p.numel() for p in model.parameters())} parameters, "
          f"{args.threads} threads", flush=True)

    sampler = Sampler(photos, args.crop, target_mm, args.zoom, paste=(args.crop_class, paste[0]))
    run = train_steps(model, sampler, steps, args.batch, args.lr, weights,
                      rng, args.log_every, validation_line(args, spec, val_pairs), args.val_every)

    onnx_path, net, figures = measure(args, model, spec, val_pairs, (train_stems, val_stems))
    data = training_data(args, len(train_stems), base)
    setup = {"steps": steps, "weights": weights, "weights_method": weights_method, "frequencies": frequencies,
             "val_frequencies": val_frequencies, "paste": paste, "target_mm": target_mm, "ground_mm": ground_mm,
             "train_images": len(train_stems), "val_images": len(val_stems), "base": base}
    report = {"model": os.path.basename(onnx_path), "spec": spec, "licence": model_licence(data), "training_data": data,
              "validation": figures["validation"], "training_set": figures["training_set"],
              "report": overlays(args, net, spec, figures["validation"]), "export": figures["export"],
              "inference": figures["inference"], "training": training_record(args, argv, run, setup)}
    report["training"]["total_s"] = round(time.time() - started, 1)
    json_path = os.path.join(args.out, args.name + ".json")
    write_json(json_path, report)
    save_checkpoint(os.path.join(args.out, args.name + ".pt"), model, args.class_names,
                    {"ground_mm_per_px": spec["ground_mm_per_px"], "training_data": data, "licence": report["licence"]},
                    width=WIDTH)
    summarise(report, onnx_path)
    if args.install:
        try:
            drop_in = install(onnx_path, json_path, args.name, args.install, figures["validation"]["zones"]["best"])
        except OSError as error:
            raise SystemExit(f"--install {args.install}: {error} (the model is in {args.out}; run as root?)")
        print(f"installed into {os.path.abspath(args.install)}; {drop_in} selects it "
              f"(check: weedsprayd --check-config)")


def summarise(report, onnx_path):
    v = report["validation"]
    best = v["zones"]["best"]
    intervals = v["intervals"]["iou"]
    ious = ", ".join(f"{n} {x} [{'-' if intervals[n] is None else f'{intervals[n][0]}-{intervals[n][1]}'}]"
                     for n, x in v["iou"].items())
    print(f"{onnx_path}: validation IoU {ious}, MIoU {v['miou']}; zones at threshold {best['threshold']}: "
          f"recall {best['recall']}, crop-only left dry {best['crop_only_left_dry']}, "
          f"bare left dry {best['bare_left_dry']}; MIoU with the labels' plant outline "
          f"{v['limits']['true_outline']['miou']}, with the labels' classes {v['limits']['true_classes']['miou']}; "
          f"forward {report['inference']['forward_ms_1_thread']} ms; "
          f"OpenCV-torch diff {report['export']['opencv_vs_torch_max_abs_diff']:.2e}; "
          f"{format_seconds(report['training']['total_s'])} in all; worst photos in {report['report']['folder']}/",
          flush=True)


if __name__ == "__main__":
    main()
