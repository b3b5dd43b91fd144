# SPDX-License-Identifier: Apache-2.0
"""The training loss and its class weights.

Loss: class-weighted cross-entropy + soft Dice (mean over classes), both over labelled pixels
only: 255 (unlabelled) is cross-entropy's ignore_index and is left out of Dice's sums. A batch
with no labelled pixel gives 0 (with gradients of zero), not NaN.

Class weights "auto": w_c = sqrt(f_max / f_c) from the training masks' pixel shares f_c (the most
frequent class gets 1), clipped to [1, 20]. A crop covering 2 % of the pixels next to 90 % soil
gets ~6.7, so it is learnt rather than drowned; a class without any training pixel gets 20
(its weight then changes nothing).
"""

import numpy as np
import torch
import torch.nn.functional as F

IGNORE = 255
MIN_WEIGHT, MAX_WEIGHT = 1.0, 20.0


def auto_class_weights(frequencies):
    """Inverse-sqrt-frequency weights relative to the most frequent class, clipped to [1, 20]."""
    frequencies = np.asarray(frequencies, np.float64)
    top = frequencies.max() if frequencies.size else 0.0
    with np.errstate(divide="ignore"):
        weights = np.where(frequencies > 0, np.sqrt(top / np.maximum(frequencies, 1e-12)), MAX_WEIGHT)
    return [round(float(w), 3) for w in np.clip(weights, MIN_WEIGHT, MAX_WEIGHT)]


def parse_class_weights(text, classes):
    """"auto" -> None (computed from the masks later); "1,1.5,4" -> list of floats."""
    if text.strip().lower() == "auto":
        return None
    try:
        weights = [float(v) for v in text.split(",")]
    except ValueError:
        raise ValueError(f"--class-weights '{text}': expected 'auto' or one number per class")
    if len(weights) != classes:
        raise ValueError(f"--class-weights has {len(weights)} values for {classes} classes")
    return weights


def loss_fn(logits, target, class_weights):
    """Weighted cross-entropy + soft Dice over the labelled pixels of target (N x H x W ids).
    Logits smaller than the target (a detail network's) are enlarged to it bilinearly."""
    if logits.shape[2:] != target.shape[1:]:
        logits = F.interpolate(logits, size=target.shape[1:], mode="bilinear", align_corners=False)
    labelled = target != IGNORE
    if not bool(labelled.any()):
        return logits.sum() * 0.0
    cross_entropy = F.cross_entropy(logits, target, weight=class_weights, ignore_index=IGNORE)
    probabilities = logits.softmax(dim=1) * labelled.unsqueeze(1)
    safe = torch.where(labelled, target, torch.zeros_like(target))
    one_hot = F.one_hot(safe, logits.shape[1]).permute(0, 3, 1, 2).float() * labelled.unsqueeze(1)
    intersection = (probabilities * one_hot).sum(dim=(0, 2, 3))
    total = probabilities.sum(dim=(0, 2, 3)) + one_hot.sum(dim=(0, 2, 3))
    dice = 1.0 - ((2 * intersection + 1.0) / (total + 1.0)).mean()
    return cross_entropy + dice
