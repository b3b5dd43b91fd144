#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""Trains the plant/soil base network on all shared photo sets, for train.py --base.

A field's own model learns from 25-40 photos; starting from a network that already tells
plants from soil at the right ground scale is what makes that enough. This network learns two
classes, soil (0) and plant (1), from every set in datasets.json:
- EWS wheat: plant / soil as labelled;
- peanut: crop and weed -> plant;
- cauliflower: crop -> plant; its 0 pixels are soil or unlabelled weeds, so those a colour
  index calls green are ignored and the rest is soil (datasets.py).
Each photo is resampled from its set's ground scale (datasets.json: mm_per_px, an estimate per
set) to --target-mm-per-px, with a wide random zoom (--zoom, 0.5-2x) so the base also suits
fine-tuning at other scales; each set gets an equal share of the crops whatever its size.
Photos in a set's held_out_list (peanut: tools/train/splits/peanut-val.txt) and --val-per-dataset
seeded others are never learnt from; plant IoU on them is reported per set.

    /usr/bin/python3 tools/train/train_base.py --out models --name base-plant-soil

(default 12000 steps: about 50 min at the ~4 steps/s of the project's 2-core machine when
idle, hours when it is busy; a progress line every --log-every steps shows steps/s and the time
left; it holds all photos in memory, about 1.7 GB). Writes OUT/NAME.pt (the checkpoint train.py --base reads) and
OUT/NAME.json: classes, ground_mm_per_px, training_data (each set's folder, count, licence,
attribution and ground scale), licence (CC BY-SA 4.0: it learnt from CC BY-SA 4.0 sets), the
held-out figures and the training command. A model fine-tuned from it lists this data too.
"""

import argparse
import json
import os
import shlex
import sys
import time

import cv2
import numpy as np
import torch
import torchvision

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from datasets import BASE_CLASSES, REPO_ROOT, TABLE, load_table, model_licence, plant_soil_mask  # noqa: E402
from evaluate import IMAGE_SUFFIXES, find_image, read_list  # noqa: E402
from loss import auto_class_weights  # noqa: E402
from model import SegmentationNet, save_checkpoint  # noqa: E402
from sampling import MEAN_RGB, SCALE, Sampler, ScaledPhoto, class_frequencies  # noqa: E402
from train import STRIDE, WIDTH, parse_range, parse_size, positive  # noqa: E402
from trainer import format_seconds, quick_iou, train_steps  # noqa: E402

DEFAULT_STEPS = 12000


def parse_args(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="models", help="folder for NAME.pt and NAME.json")
    parser.add_argument("--name", default="base-plant-soil")
    parser.add_argument("--steps", type=positive(int), default=DEFAULT_STEPS)
    parser.add_argument("--seed", type=int, default=9)
    parser.add_argument("--target-mm-per-px", type=positive(float), default=1.0, help="ground mm per network pixel")
    parser.add_argument("--zoom", type=parse_range, default=(0.5, 2.0), help="random zoom around the target scale")
    parser.add_argument("--crop", type=parse_size, default=(256, 192), help="training crop WxH")
    parser.add_argument("--batch", type=positive(int), default=8)
    parser.add_argument("--lr", type=positive(float), default=4e-3)
    parser.add_argument("--threads", type=positive(int), default=2)
    parser.add_argument("--val-per-dataset", type=int, default=8,
                        help="held-out photos per set without a held_out_list")
    parser.add_argument("--max-per-dataset", type=int, default=0,
                        help="learn from at most this many photos per set (0: all)")
    parser.add_argument("--datasets", help="comma-separated set names (default: all in the table)")
    parser.add_argument("--data-root", help="folder holding the sets (default: as datasets.json's paths say)")
    parser.add_argument("--table", default=TABLE, help="the data sets' table")
    parser.add_argument("--log-every", type=positive(int), default=25)
    parser.add_argument("--val-every", type=positive(int), default=500)
    return parser.parse_args(argv)


def set_stems(entry):
    images = os.path.join(entry["abs_path"], entry["images"])
    masks = os.path.join(entry["abs_path"], entry["masks"])
    if not os.path.isdir(images) or not os.path.isdir(masks):
        raise SystemExit(f"{entry['name']}: no {images} or {masks} (set --data-root?)")
    stems = sorted(os.path.splitext(n)[0] for n in os.listdir(images) if n.endswith(IMAGE_SUFFIXES))
    return [s for s in stems if os.path.exists(os.path.join(masks, s + ".png"))]


def split_set(entry, stems, args, rng):
    """(train stems, held-out stems) of one set."""
    if entry.get("held_out_list"):
        held = set(read_list(os.path.join(REPO_ROOT, entry["held_out_list"])))
        held_out = [s for s in stems if s in held]
    else:
        held_out = sorted(rng.choice(stems, size=min(args.val_per_dataset, len(stems) - 1), replace=False).tolist())
    train = [s for s in stems if s not in set(held_out)]
    if args.max_per_dataset > 0:
        train = sorted(rng.choice(train, size=min(args.max_per_dataset, len(train)), replace=False).tolist())
    return train, held_out


def read_base_pair(entry, stem):
    """(BGR photo, plant/soil mask) of one photo of a set."""
    image = cv2.imread(find_image(os.path.join(entry["abs_path"], entry["images"]), stem), cv2.IMREAD_COLOR)
    mask_path = os.path.join(entry["abs_path"], entry["masks"], stem + ".png")
    mask = cv2.imread(mask_path, cv2.IMREAD_UNCHANGED)
    if image is None or mask is None or mask.shape != image.shape[:2]:
        raise SystemExit(f"{entry['name']}: cannot read {stem} or its mask {mask_path} (or sizes differ)")
    return image, plant_soil_mask(entry, image, mask)


def load_sets(entries, args, rng):
    """Training photos, their sampling weights, held-out samples per set and the data records."""
    photos, weights, held_out, records = [], [], {}, []
    for entry in entries:
        train, held = split_set(entry, set_stems(entry), args, rng)
        for stem in train:
            image, mask = read_base_pair(entry, stem)
            photos.append(ScaledPhoto(image, mask, entry["mm_per_px"], args.target_mm_per_px))
            weights.append(1.0 / len(train))
        held_out[entry["name"]] = [read_base_pair(entry, s) + (entry["mm_per_px"],) for s in held]
        records.append({"images": entry["path"], "count": len(train), "licence": entry["licence"],
                        "attribution": entry["attribution"], "mm_per_px": entry["mm_per_px"],
                        "mm_per_px_estimate": entry["mm_per_px_estimate"], "held_out": len(held)})
        print(f"{entry['name']}: {len(train)} photos to learn from, {len(held)} held out, "
              f"{entry['mm_per_px']} mm/px ({entry['mm_per_px_estimate']})", flush=True)
    return photos, weights, held_out, records


def base_spec(args):
    return {"input_width": args.crop[0], "input_height": args.crop[1], "stride": STRIDE, "mean_rgb": list(MEAN_RGB),
            "scale": SCALE, "rgb": True, "classes": list(BASE_CLASSES), "ground_mm_per_px": args.target_mm_per_px}


def held_out_figures(model, held_out, spec):
    figures = {}
    for name, samples in held_out.items():
        if samples:
            iou = quick_iou(model, samples, spec)
            figures[name] = {"images": len(samples), "iou": {c: round(float(v), 4) for c, v in zip(BASE_CLASSES, iou)}}
    return figures


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    args = parse_args(argv)
    started = time.time()
    torch.set_num_threads(args.threads)
    cv2.setNumThreads(1)
    torch.manual_seed(args.seed)
    rng = np.random.default_rng(args.seed)
    entries = load_table(args.table, args.data_root)
    if args.datasets:
        wanted = args.datasets.split(",")
        unknown = sorted(set(wanted) - {e["name"] for e in entries})
        if unknown:
            raise SystemExit(f"--datasets: {', '.join(unknown)} not in {args.table}")
        entries = [e for e in entries if e["name"] in wanted]
    photos, weights, held_out, records = load_sets(entries, args, rng)
    frequencies = class_frequencies([p.mask for p in photos], len(BASE_CLASSES))
    class_weights = auto_class_weights(frequencies)
    print(f"{len(photos)} photos at {args.target_mm_per_px} mm/px; plant share {frequencies[1]:.1%}, "
          f"weights {class_weights}; {args.steps} steps of {args.batch}", flush=True)
    spec = base_spec(args)

    def validate(net):
        figures = held_out_figures(net, held_out, spec)
        return "held-out plant IoU " + " ".join(f"{n} {f['iou']['plant']:.3f}" for n, f in figures.items())

    model = SegmentationNet(len(BASE_CLASSES), width=WIDTH)
    sampler = Sampler(photos, args.crop, args.target_mm_per_px, args.zoom, weights)
    run = train_steps(model, sampler, args.steps, args.batch, args.lr, class_weights, rng,
                      args.log_every, validate, args.val_every)
    description = {
        "classes": list(BASE_CLASSES),
        "ground_mm_per_px": args.target_mm_per_px,
        "licence": model_licence(records),
        "training_data": records,
        "held_out": held_out_figures(model, held_out, spec),
        "training": {
            "command": " ".join(["/usr/bin/python3", "tools/train/train_base.py"] + [shlex.quote(a) for a in argv]),
            "seed": args.seed, "steps": args.steps, "batch": args.batch, "crop": list(args.crop), "lr": args.lr,
            "zoom": list(args.zoom), "class_weights": class_weights,
            "class_shares": {c: round(float(f), 4) for c, f in zip(BASE_CLASSES, frequencies)},
            "threads": args.threads, "steps_per_s": run["steps_per_s"], "wall_s": run["wall_s"],
            "total_s": round(time.time() - started, 1), "torch": torch.__version__,
            "torchvision": torchvision.__version__, "opencv": cv2.__version__, "pretrained_weights": None,
        },
    }
    os.makedirs(args.out, exist_ok=True)
    checkpoint = os.path.join(args.out, args.name + ".pt")
    save_checkpoint(checkpoint, model, BASE_CLASSES, description, width=WIDTH)
    with open(os.path.join(args.out, args.name + ".json"), "w") as out:
        json.dump(description, out, indent=2)
        out.write("\n")
    print(f"{checkpoint}: held-out {description['held_out']}; {format_seconds(description['training']['total_s'])} "
          f"in all; licence {description['licence']}", flush=True)


if __name__ == "__main__":
    main()
