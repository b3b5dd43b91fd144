# SPDX-License-Identifier: Apache-2.0
"""limits.py: the labels' outline with the model's classes, and the model's outline with the
labels' classes; and evaluate.py's --limits figures built from them."""

import unittest

import numpy as np

import evaluate
import limits

SOIL, CROP, WEED = 0, 1, 2


def scene():
    """A 20 x 30 label image: a crop plant, a weed, an unlabelled strip."""
    truth = np.zeros((20, 30), np.uint8)
    truth[2:10, 2:12] = CROP
    truth[12:16, 20:24] = WEED
    truth[:, 28:] = evaluate.IGNORE
    return truth


def scores_for(labels):
    """classes x H x W scores whose argmax is labels."""
    scores = np.zeros((3,) + labels.shape, np.float32)
    for c in range(3):
        scores[c][labels == c] = 1.0
    return scores


class TrueOutlineTest(unittest.TestCase):
    def test_labelled_plants_get_the_models_best_plant_class_even_where_it_saw_soil(self):
        truth = scene()
        predicted = truth.copy()
        predicted[predicted == evaluate.IGNORE] = SOIL
        predicted[12:16, 20:24] = SOIL  # the model missed the weed ...
        scores = scores_for(predicted)
        scores[WEED, 12:16, 20:24] = 0.4  # ... though weed led crop there
        scores[CROP, 12:16, 20:24] = 0.1
        predicted[2:4, 2:12] = WEED  # and called part of the crop weed
        scores[:, 2:4, 2:12] = scores_for(predicted)[:, 2:4, 2:12]
        predicted[0, 20:25] = CROP  # a crop pixel on soil
        scores[:, 0, 20:25] = scores_for(predicted)[:, 0, 20:25]
        labels = limits.true_outline(truth, scores, SOIL)
        self.assertTrue(np.all(labels[12:16, 20:24] == WEED))
        self.assertTrue(np.all(labels[2:4, 2:12] == WEED))
        self.assertTrue(np.all(labels[4:10, 2:12] == CROP))
        self.assertTrue(np.all(labels[0, 20:25] == SOIL))
        self.assertTrue(np.all(labels[:, 28:] == SOIL))  # unlabelled: never plant


class TrueClassesTest(unittest.TestCase):
    def test_the_models_plants_take_the_labels_or_the_nearest_labelled_plants_class(self):
        truth = scene()
        predicted = np.zeros_like(truth)
        predicted[1:11, 1:13] = WEED  # the crop, called weed and outlined a pixel too wide
        predicted[12:17, 19:25] = CROP  # the weed, called crop and a pixel too wide
        predicted[14, 20] = SOIL  # a hole in it
        labels = limits.true_classes(truth, predicted, SOIL)
        self.assertTrue(np.all(labels[1:11, 1:13] == CROP))  # its spill onto soil too
        self.assertTrue(np.all(labels[12:17, 19:25][predicted[12:17, 19:25] != SOIL] == WEED))
        self.assertEqual(labels[14, 20], SOIL)  # the model's outline is kept, holes and all
        self.assertTrue(np.all(labels[predicted == SOIL] == SOIL))

    def test_without_a_labelled_plant_the_models_classes_stay(self):
        truth = np.zeros((8, 8), np.uint8)
        predicted = np.full((8, 8), WEED, np.uint8)
        self.assertTrue(np.array_equal(limits.true_classes(truth, predicted, SOIL), predicted))


class EvaluateLimitsTest(unittest.TestCase):
    def test_limits_separate_an_outline_error_from_a_class_error(self):
        truth = scene()
        # Model A outlines every plant right but swaps crop and weed; model B classes right but
        # outlines each plant with a one-pixel rim of extra plant on the soil.
        swapped = np.where(truth == CROP, WEED, np.where(truth == WEED, CROP, truth)).astype(np.uint8)
        swapped[truth == evaluate.IGNORE] = SOIL
        rimmed = np.zeros_like(truth)
        rimmed[1:11, 1:13] = CROP
        rimmed[11:17, 19:25] = WEED
        figures = {}
        for name, predicted in (("swapped", swapped), ("rimmed", rimmed)):
            scores = evaluate.Scores(["soil", "crop", "weed"], CROP, WEED, SOIL)
            scores.add(name, truth, predicted, scores_for(predicted))
            figures[name] = scores.summary()
        swap, rim = figures["swapped"], figures["rimmed"]
        self.assertEqual(swap["iou"]["weed"], 0.0)
        self.assertEqual(swap["limits"]["true_classes"]["miou"], 1.0)  # the outline was right
        self.assertEqual(swap["limits"]["true_outline"]["iou"]["weed"], 0.0)  # the class was not
        self.assertLess(rim["iou"]["weed"], 0.5)
        self.assertEqual(rim["limits"]["true_outline"]["miou"], 1.0)  # the class was right
        self.assertLess(rim["limits"]["true_classes"]["iou"]["weed"], 0.5)  # the outline was not

    def test_no_limits_unless_asked(self):
        scores = evaluate.Scores(["soil", "crop", "weed"], CROP, WEED)
        scores.add("a", scene(), np.zeros((20, 30), np.uint8))
        self.assertNotIn("limits", scores.summary())


if __name__ == "__main__":
    unittest.main()
