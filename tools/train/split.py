#!/usr/bin/python3
"""Seeded train/validation split of a folder of images: writes two lists of image stems.

    /usr/bin/python3 tools/train/split.py --images ../shared/data/peanut/images --val 60 --seed 9 \
        --train-out tools/train/splits/peanut-train.txt --val-out tools/train/splits/peanut-val.txt
"""

import argparse
import os
import random

IMAGE_SUFFIXES = (".jpg", ".jpeg", ".png", ".bmp", ".tif", ".tiff")


def image_stems(folder):
    stems = [os.path.splitext(name)[0] for name in os.listdir(folder) if name.lower().endswith(IMAGE_SUFFIXES)]
    if not stems:
        raise SystemExit(f"--images {folder}: no images ({', '.join(IMAGE_SUFFIXES)})")
    return sorted(stems)


def write_list(path, stems):
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    with open(path, "w") as out:
        out.write("".join(stem + "\n" for stem in sorted(stems)))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--images", required=True, help="folder of images")
    parser.add_argument("--val", type=int, required=True, help="number of validation images")
    parser.add_argument("--seed", type=int, required=True)
    parser.add_argument("--train-out", required=True)
    parser.add_argument("--val-out", required=True)
    args = parser.parse_args()
    stems = image_stems(args.images)
    if not 0 < args.val < len(stems):
        raise SystemExit(f"--val {args.val}: must be between 1 and {len(stems) - 1} ({len(stems)} images)")
    shuffled = list(stems)
    random.Random(args.seed).shuffle(shuffled)
    write_list(args.val_out, shuffled[: args.val])
    write_list(args.train_out, shuffled[args.val :])
    print(f"{len(stems) - args.val} train -> {args.train_out}, {args.val} validation -> {args.val_out}")


if __name__ == "__main__":
    main()
