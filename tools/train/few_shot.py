#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""A few-shot cut of a labelled set: --count training photos drawn (seeded) from --pool, none of
them a near-duplicate (split.py's test) of a photo in --val-list, so that the validation photos
show plants the model never saw. Measures how a field's own model does from a few photos:

    /usr/bin/python3 tools/train/few_shot.py --images ../shared/data/peanut/images \
        --pool tools/train/splits/peanut-train.txt --val-list tools/train/splits/peanut-val.txt \
        --count 32 --seed 9 --out tools/train/splits/peanut-few32.txt \
        --val-out tools/train/splits/peanut-val-unshared.txt

--val-out (optional) writes the validation photos that have no near-duplicate anywhere in the
pool (the stricter set to report on).
"""

import argparse
import os
import random
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from evaluate import read_list  # noqa: E402
from split import image_paths, near_duplicate_groups, write_list  # noqa: E402


def parse_args(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--images", required=True, help="folder of the photos")
    parser.add_argument("--pool", required=True, help="stems the training photos are drawn from")
    parser.add_argument("--val-list", required=True, help="validation stems")
    parser.add_argument("--count", type=int, required=True, help="training photos to draw")
    parser.add_argument("--seed", type=int, required=True)
    parser.add_argument("--out", required=True, help="the training list written")
    parser.add_argument("--val-out", help="the validation photos without a near-duplicate in the pool")
    return parser.parse_args(argv)


def main(argv=None):
    args = parse_args(argv)
    pool, val = read_list(args.pool), read_list(args.val_list)
    paths = {s: p for s, p in image_paths(args.images).items() if s in set(pool) | set(val)}
    missing = sorted((set(pool) | set(val)) - set(paths))
    if missing:
        raise SystemExit(f"--images {args.images}: no photo for '{missing[0]}' ({len(missing)} missing)")
    groups = near_duplicate_groups(paths)
    val_set = set(val)
    touching = {s for g in groups if val_set & set(g) for s in g}
    candidates = sorted(s for s in pool if s not in touching)
    if len(candidates) < args.count:
        raise SystemExit(f"--count {args.count}: only {len(candidates)} pool photos share no plants with --val-list")
    chosen = random.Random(args.seed).sample(candidates, args.count)
    write_list(args.out, chosen)
    shared = sorted(s for g in groups if val_set & set(g) and set(g) - val_set for s in g if s in val_set)
    print(f"{len(chosen)} of {len(candidates)} pool photos -> {args.out}; "
          f"{len(pool) - len(candidates)} pool photos left out as near-duplicates of validation photos; "
          f"{len(shared)} validation photos have a near-duplicate in the pool")
    if args.val_out:
        write_list(args.val_out, [s for s in val if s not in set(shared)])


if __name__ == "__main__":
    main()
