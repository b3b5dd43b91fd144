# SPDX-License-Identifier: Apache-2.0
"""tools/train/split.py: near-duplicate photos stay on one side of the split."""

import contextlib
import io
import os
import tempfile
import unittest

import cv2
import numpy as np

import few_shot
import split
from synthetic import field_photo


def read_stems(path):
    with open(path) as lines:
        return {line.strip() for line in lines if line.strip()}


class NearDuplicates(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.images = os.path.join(self.tmp.name, "images")
        os.makedirs(self.images)
        for i in range(10):
            image, _ = field_photo(100 + i, 240, 180)
            cv2.imwrite(os.path.join(self.images, f"p{i:02d}.png"), image)
        # p10: p03 again, re-encoded as JPEG and a little brighter (the same photo twice).
        again = cv2.imread(os.path.join(self.images, "p03.png"))
        cv2.imwrite(os.path.join(self.images, "p10.jpg"), np.clip(again * 1.05, 0, 255).astype(np.uint8))

    def tearDown(self):
        self.tmp.cleanup()

    def test_duplicate_pair_is_one_group(self):
        groups = split.near_duplicate_groups(split.image_paths(self.images))
        self.assertIn(["p03", "p10"], groups)
        self.assertEqual(sum(map(len, groups)), 11)

    def test_pair_stays_together_whatever_the_seed(self):
        for seed in range(6):
            train_out = os.path.join(self.tmp.name, f"train{seed}.txt")
            val_out = os.path.join(self.tmp.name, f"val{seed}.txt")
            with contextlib.redirect_stdout(io.StringIO()) as printed:
                split.main(["--images", self.images, "--val-fraction", "0.3", "--seed", str(seed),
                            "--train-out", train_out, "--val-out", val_out])
            train, val = read_stems(train_out), read_stems(val_out)
            self.assertEqual(len(train | val), 11)
            self.assertFalse(train & val)
            self.assertEqual("p03" in val, "p10" in val, f"seed {seed}")
            self.assertIn("p03 p10", printed.getvalue())

    def test_few_shot_cut_leaves_out_photos_of_the_validation_plants(self):
        lists = {name: os.path.join(self.tmp.name, name + ".txt") for name in ("pool", "val", "few", "unshared")}
        with open(lists["pool"], "w") as out:
            out.write("".join(f"p{i:02d}\n" for i in (0, 1, 2, 3, 4, 5, 6)))
        with open(lists["val"], "w") as out:
            out.write("p07\np08\np10\n")  # p10 shows p03's plants
        with contextlib.redirect_stdout(io.StringIO()):
            few_shot.main(["--images", self.images, "--pool", lists["pool"], "--val-list", lists["val"],
                           "--count", "6", "--seed", "1", "--out", lists["few"], "--val-out", lists["unshared"]])
        self.assertEqual(read_stems(lists["few"]), {"p00", "p01", "p02", "p04", "p05", "p06"})
        self.assertEqual(read_stems(lists["unshared"]), {"p07", "p08"})
        with self.assertRaises(SystemExit):  # only 6 pool photos share no plants with validation
            few_shot.main(["--images", self.images, "--pool", lists["pool"], "--val-list", lists["val"],
                           "--count", "7", "--seed", "1", "--out", lists["few"]])

    def test_only_photos_with_masks(self):
        masks = os.path.join(self.tmp.name, "masks")
        os.makedirs(masks)
        for stem in ("p00", "p01", "p02"):
            cv2.imwrite(os.path.join(masks, stem + ".png"), np.zeros((4, 4), np.uint8))
        self.assertEqual(list(split.image_paths(self.images, masks)), ["p00", "p01", "p02"])


if __name__ == "__main__":
    unittest.main()
