#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""Seeded train/validation split of a folder of photos that keeps near-duplicates on one side.

Two photos are near-duplicates when
- their small grey thumbnails (32 x 24, each normalised to mean 0 and deviation 1) differ by
  less than THUMBNAIL_DISTANCE on average (the same photo, re-encoded, resized or re-exposed), or
- they share at least --min-inliers ORB feature matches (cv2.ORB on copies 480 px wide,
  BFMatcher with Lowe's ratio test, then the inliers of a RANSAC homography): the same plants
  seen twice, e.g. from overlapping positions.
Near-duplicates are joined (union-find) into groups, the groups are shuffled with --seed and
whole groups go to validation until it holds --val photos (or --val-fraction of them); so no
validation photo shows what a training photo shows. The groups found are printed.

    /usr/bin/python3 tools/train/split.py --images ../shared/data/peanut/images --val 60 --seed 9 \
        --train-out tools/train/splits/peanut-train.txt --val-out tools/train/splits/peanut-val.txt

ORB matching compares every pair: about a minute for 320 photos on 2 cores, well under a
second for 40. --no-features keeps only the thumbnail test. --masks lists only photos that
have a STEM.png mask there.
"""

import argparse
import itertools
import os
import random

import cv2
import numpy as np

IMAGE_SUFFIXES = (".jpg", ".jpeg", ".png", ".bmp", ".tif", ".tiff")
THUMBNAIL_SIZE = (32, 24)
THUMBNAIL_DISTANCE = 0.25
FEATURE_WIDTH = 480
FEATURES = 400
RATIO = 0.75
MIN_INLIERS = 20
RANSAC_PX = 4.0


def image_paths(folder, masks=None):
    """{stem: path} of the photos in folder (only those with masks/STEM.png when masks is given)."""
    paths = {os.path.splitext(name)[0]: os.path.join(folder, name)
             for name in sorted(os.listdir(folder)) if name.lower().endswith(IMAGE_SUFFIXES)}
    if masks:
        paths = {s: p for s, p in paths.items() if os.path.exists(os.path.join(masks, s + ".png"))}
    if not paths:
        raise SystemExit(f"--images {folder}: no images ({', '.join(IMAGE_SUFFIXES)})"
                         + (f" with a mask in {masks}" if masks else ""))
    return dict(sorted(paths.items()))


def image_stems(folder):
    return list(image_paths(folder))


def read_grey(path):
    grey = cv2.imread(path, cv2.IMREAD_GRAYSCALE)
    if grey is None:
        raise SystemExit(f"{path}: cannot read")
    return grey


def thumbnail(grey):
    small = cv2.resize(grey, THUMBNAIL_SIZE, interpolation=cv2.INTER_AREA).astype(np.float32).ravel()
    return (small - small.mean()) / (small.std() + 1e-6)


def thumbnail_pairs(thumbnails, max_distance=THUMBNAIL_DISTANCE):
    """(i, j) pairs whose thumbnails differ by less than max_distance on average."""
    stack = np.stack(thumbnails)
    pairs = []
    for i in range(len(stack) - 1):
        distances = np.abs(stack[i + 1 :] - stack[i]).mean(axis=1)
        pairs += [(i, i + 1 + int(k)) for k in np.nonzero(distances < max_distance)[0]]
    return pairs


def orb_features(grey, orb):
    scale = FEATURE_WIDTH / grey.shape[1]
    if scale < 1:
        grey = cv2.resize(grey, None, fx=scale, fy=scale, interpolation=cv2.INTER_AREA)
    keypoints, descriptors = orb.detectAndCompute(grey, None)
    return np.float32([k.pt for k in keypoints]), descriptors


def shared_inliers(a, b, matcher):
    """RANSAC homography inliers among the ratio-test matches of two (points, descriptors)."""
    (points_a, desc_a), (points_b, desc_b) = a, b
    if desc_a is None or desc_b is None or len(desc_a) < 2 or len(desc_b) < 2:
        return 0
    good = [m for m, n in (pair for pair in matcher.knnMatch(desc_a, desc_b, k=2) if len(pair) == 2)
            if m.distance < RATIO * n.distance]
    if len(good) < 4:
        return 0
    source = points_a[[m.queryIdx for m in good]]
    target = points_b[[m.trainIdx for m in good]]
    _, inliers = cv2.findHomography(source, target, cv2.RANSAC, RANSAC_PX)
    return int(inliers.sum()) if inliers is not None else 0


def feature_pairs(features, min_inliers=MIN_INLIERS):
    """(i, j, inliers) of the photo pairs sharing at least min_inliers matched features."""
    matcher = cv2.BFMatcher(cv2.NORM_HAMMING)
    pairs = []
    for i, j in itertools.combinations(range(len(features)), 2):
        inliers = shared_inliers(features[i], features[j], matcher)
        if inliers >= min_inliers:
            pairs.append((i, j, inliers))
    return pairs


class UnionFind:
    def __init__(self, size):
        self.parent = list(range(size))

    def find(self, i):
        while self.parent[i] != i:
            self.parent[i] = self.parent[self.parent[i]]
            i = self.parent[i]
        return i

    def union(self, i, j):
        self.parent[self.find(i)] = self.find(j)


def near_duplicate_groups(paths, use_features=True, min_inliers=MIN_INLIERS):
    """Groups (lists of stems, sorted) of near-duplicate photos; single photos are groups of 1."""
    stems = list(paths)
    greys = [read_grey(paths[s]) for s in stems]
    links = thumbnail_pairs([thumbnail(g) for g in greys])
    if use_features:
        orb = cv2.ORB_create(nfeatures=FEATURES)
        links += [(i, j) for i, j, _ in feature_pairs([orb_features(g, orb) for g in greys], min_inliers)]
    sets = UnionFind(len(stems))
    for i, j in links:
        sets.union(i, j)
    groups = {}
    for i, stem in enumerate(stems):
        groups.setdefault(sets.find(i), []).append(stem)
    return sorted(groups.values())


def split_groups(groups, val_count, seed):
    """(train stems, val stems): shuffled whole groups fill validation up to val_count photos."""
    order = list(groups)
    random.Random(seed).shuffle(order)
    train, val = [], []
    for group in order:
        (val if len(val) + len(group) <= val_count else train).extend(group)
    return sorted(train), sorted(val)


def write_list(path, stems):
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    with open(path, "w") as out:
        out.write("".join(stem + "\n" for stem in sorted(stems)))


def validation_count(args, total):
    count = args.val if args.val is not None else int(round(args.val_fraction * total))
    if not 0 < count < total:
        raise SystemExit(f"validation size {count}: must be between 1 and {total - 1} ({total} images)")
    return count


def parse_args(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--images", required=True, help="folder of images")
    parser.add_argument("--masks", help="only photos with a STEM.png mask in this folder")
    size = parser.add_mutually_exclusive_group(required=True)
    size.add_argument("--val", type=int, help="number of validation images")
    size.add_argument("--val-fraction", type=float, help="share of the images for validation, e.g. 0.25")
    parser.add_argument("--seed", type=int, required=True)
    parser.add_argument("--train-out", required=True)
    parser.add_argument("--val-out", required=True)
    parser.add_argument("--no-features", action="store_true", help="group by thumbnails only (no ORB matching)")
    parser.add_argument("--min-inliers", type=int, default=MIN_INLIERS,
                        help="shared ORB inliers that make two photos one group")
    return parser.parse_args(argv)


def main(argv=None):
    args = parse_args(argv)
    paths = image_paths(args.images, args.masks)
    count = validation_count(args, len(paths))
    groups = near_duplicate_groups(paths, not args.no_features, args.min_inliers)
    shared = [g for g in groups if len(g) > 1]
    print(f"{len(shared)} groups of near-duplicate photos ({sum(map(len, shared))} photos):")
    for group in shared:
        print("  " + " ".join(group))
    biggest = max(map(len, groups))
    if biggest > count:
        print(f"warning: a group of {biggest} photos is larger than the validation set ({count}): it stays in training")
    train, val = split_groups(groups, count, args.seed)
    write_list(args.val_out, val)
    write_list(args.train_out, train)
    print(f"{len(train)} train -> {args.train_out}, {len(val)} validation -> {args.val_out}")


if __name__ == "__main__":
    main()
