# SPDX-License-Identifier: Apache-2.0
"""tools/train/grid_ceiling.py: what a perfect network deciding on a grid of G mm can score."""

import unittest

import numpy as np

from grid_ceiling import grid_iou, pooled_labels


class GridCeiling(unittest.TestCase):
    def setUp(self):
        self.mask = np.zeros((96, 96), np.uint8)
        self.mask[8:40, 8:40] = 1  # a crop plant 32 mm across at 1 mm/px
        self.mask[60:63, 70:73] = 2  # a weed seedling 3 mm across
        self.mask[90:, :] = 255  # unlabelled

    def test_a_grid_as_fine_as_the_mask_scores_everything(self):
        iou = grid_iou([self.mask], 3, 1.0, 1.0)
        self.assertTrue(np.allclose(iou, 1.0))

    def test_a_weed_smaller_than_the_grid_cannot_be_drawn(self):
        iou = grid_iou([self.mask], 3, 1.0, 8.0)
        self.assertEqual(iou[2], 0.0)
        self.assertGreater(iou[1], 0.75)  # the plant, a few cells wide, stays

    def test_pooling_takes_the_class_with_most_area_and_keeps_the_size(self):
        labels = pooled_labels(self.mask, 3, (12, 12))
        self.assertEqual(labels.shape, self.mask.shape)
        self.assertEqual(labels[20, 20], 1)
        self.assertEqual(labels[61, 71], 0)


if __name__ == "__main__":
    unittest.main()
