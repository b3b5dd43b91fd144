# SPDX-License-Identifier: Apache-2.0
"""What limits a model: its plant outline or its choice of class (evaluate.py --limits).

Two figures beside the model's own, each with one half of the job taken from the labels:
- true_outline: the labels say which pixels are plant (any class but soil), the model which of
  its plant classes each is (the best-scoring class other than soil, even where it called the
  pixel soil). Where this is high and the model's own figure low, the model finds the plants
  poorly (a finer input, a finer decision, more photos of small weeds help); the choice is sound.
- true_classes: the model says which pixels are plant, the labels which class: a pixel the model
  calls plant that is labelled plant keeps its label; one labelled soil takes the class of the
  nearest labelled plant pixel (the plant the model's outline spilled from). Where this is high,
  the outline is sound and the choice of class is what fails (more labelled photos of the crop).
Unlabelled pixels (255) count in neither, as in every figure of evaluate.py.
"""

import cv2
import numpy as np

from labels import IGNORE


def true_outline(truth, scores, soil_class):
    """Class ids: soil where the labels say soil, else the model's best non-soil class."""
    plant_scores = scores.copy()
    plant_scores[soil_class] = -np.inf
    choice = plant_scores.argmax(axis=0).astype(np.uint8)
    labelled_plant = (truth != soil_class) & (truth != IGNORE)
    return np.where(labelled_plant, choice, soil_class).astype(np.uint8)


def true_classes(truth, predicted, soil_class):
    """Class ids: soil where the model says soil, else the label of the pixel or, on labelled
    soil, of the nearest labelled plant pixel (the model's own class when no pixel is plant)."""
    labelled_plant = (truth != soil_class) & (truth != IGNORE)
    if not labelled_plant.any():
        return predicted.copy()
    # Each pixel's nearest labelled plant pixel: distance to the zeros of ~labelled_plant.
    _, nearest = cv2.distanceTransformWithLabels((~labelled_plant).astype(np.uint8), cv2.DIST_L2, 5,
                                                 labelType=cv2.DIST_LABEL_PIXEL)
    class_of_label = np.zeros(int(nearest.max()) + 1, np.uint8)
    ys, xs = np.nonzero(labelled_plant)
    class_of_label[nearest[ys, xs]] = truth[ys, xs]
    nearest_class = class_of_label[nearest]
    plant_class = np.where(labelled_plant, truth, nearest_class)
    return np.where(predicted != soil_class, plant_class, soil_class).astype(np.uint8)
