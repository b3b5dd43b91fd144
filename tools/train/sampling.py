# SPDX-License-Identifier: Apache-2.0
"""Training samples: photos resampled to the network's ground scale, random crops around it.

Each training photo is kept once in memory (ScaledPhoto) at CACHE_FACTOR times the target
resolution (never finer than the photo itself), so that zooming in stays sharp. A batch draws
photos with replacement (optionally weighted, e.g. to give each data set an equal share), and
from each a crop of the crop size at the target ground scale times a random zoom (log-uniform in
the zoom range, e.g. 0.7-1.4), aspect (+-15 %), rotation, flips and position; then colour, light
and camera changes another field or camera may bring (hue, saturation, white balance, exposure,
contrast, gamma, blur, sensor noise). Masks follow the geometry with nearest neighbour; 255
(unlabelled) stays 255.

Pasting (paste=(class id, probability)): with that probability a crop gets the pixels of one
class, image and label, from another crop drawn the same way from a training photo that shows
that class (the same photo can be drawn), laid over whatever is there. A crop that covers a few
per cent of the photos is then seen more often, on more kinds of ground and beside more weeds,
so the network does not learn to call a plant weed whenever in doubt.

Ground scale: a photo stored at photo_mm_per_px (ground mm per pixel) is resampled so that one
pixel covers target_mm_per_px, the scale the network is meant to run at. Without a known ground
scale, callers pass photo_mm_per_px = 1 and target_mm_per_px = photo width / input width (the
photo squeezed to the input width, as the daemon squeezes a frame of unknown scale).
"""

import math

import cv2
import numpy as np
import torch

MEAN_RGB = (123.675, 116.28, 103.53)  # ImageNet means; scale 1/58 ~ 1/std
SCALE = 1.0 / 58.0
CACHE_FACTOR = 2
IGNORE = 255


class ScaledPhoto:
    """A photo and its mask at cache resolution; mm_per_px is the cached pixel's ground size."""

    def __init__(self, image, mask, photo_mm_per_px, target_mm_per_px, cache_factor=CACHE_FACTOR):
        self.mm_per_px = max(photo_mm_per_px, target_mm_per_px / cache_factor)
        factor = photo_mm_per_px / self.mm_per_px
        if factor < 0.999:
            size = (max(1, round(image.shape[1] * factor)), max(1, round(image.shape[0] * factor)))
            image = cv2.resize(image, size, interpolation=cv2.INTER_AREA)
            mask = cv2.resize(mask, size, interpolation=cv2.INTER_NEAREST)
        self.image = image
        self.mask = mask


def log_uniform(rng, low, high):
    return math.exp(rng.uniform(math.log(low), math.log(high)))


def random_geometry(rng, image, mask, out_size, scale, zoom_range):
    """A crop of out_size: output px per source px = scale x a random zoom; random aspect,
    rotation, flip and position."""
    out_w, out_h = out_size
    src_h, src_w = image.shape[:2]
    zoom = scale * log_uniform(rng, *zoom_range)
    aspect = math.exp(rng.uniform(-0.15, 0.15))
    angle = rng.uniform(-math.pi, math.pi) if rng.random() < 0.7 else 0.0
    cos, sin = math.cos(angle), math.sin(angle)
    # Output = A * (source - centre) + output centre, A = rotation * scale * flips.
    linear = np.array([[cos, -sin], [sin, cos]]) @ np.diag([zoom * aspect, zoom / aspect])
    if rng.random() < 0.5:
        linear = linear @ np.diag([-1.0, 1.0])
    if rng.random() < 0.5:
        linear = linear @ np.diag([1.0, -1.0])
    centre = np.array([rng.uniform(0, src_w), rng.uniform(0, src_h)])
    offset = np.array([out_w / 2, out_h / 2]) - linear @ centre
    matrix = np.hstack([linear, offset[:, None]])
    warped = cv2.warpAffine(image, matrix, out_size, flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT_101)
    warped_mask = cv2.warpAffine(mask, matrix, out_size, flags=cv2.INTER_NEAREST, borderMode=cv2.BORDER_REFLECT_101)
    return warped, warped_mask


def random_photometry(rng, bgr):
    """Colour, light and camera changes; float RGB 0-255 out."""
    image = bgr.astype(np.float32) / 255.0
    hsv = cv2.cvtColor(image, cv2.COLOR_BGR2HSV)
    hsv[..., 0] = (hsv[..., 0] + rng.uniform(-15, 15)) % 360.0
    hsv[..., 1] *= rng.uniform(0.55, 1.45)
    image = cv2.cvtColor(np.clip(hsv, 0, [360, 1, 1]).astype(np.float32), cv2.COLOR_HSV2BGR)
    image *= rng.uniform(0.85, 1.15, size=3).astype(np.float32)  # white balance
    image *= rng.uniform(0.55, 1.5)  # exposure
    mean = image.mean()
    image = (image - mean) * rng.uniform(0.7, 1.3) + mean  # contrast
    image = np.clip(image, 0, 1) ** rng.uniform(0.7, 1.45)  # gamma
    if rng.random() < 0.4:
        image = cv2.GaussianBlur(image, (0, 0), rng.uniform(0.4, 1.6))
    if rng.random() < 0.5:
        image += rng.normal(0, rng.uniform(0.005, 0.04), image.shape).astype(np.float32)
    image = np.clip(image, 0, 1) * 255.0
    return image[..., ::-1]  # RGB


def normalise(rgb):
    """Float RGB 0-255 H x W x 3 -> 3 x H x W network input."""
    return ((rgb - np.array(MEAN_RGB, np.float32)) * SCALE).transpose(2, 0, 1)


def paste_class(image, mask, donor_image, donor_mask, class_id):
    """image and mask with the donor's pixels of class_id (colour and label) laid over them."""
    where = donor_mask == class_id
    if not where.any():
        return image, mask
    image, mask = image.copy(), mask.copy()
    image[where] = donor_image[where]
    mask[where] = class_id
    return image, mask


PASTE_TRIES = 4  # donor crops drawn until one shows the class (a crop can miss a small plant)


class Sampler:
    """Batches of augmented crops drawn with replacement from ScaledPhotos."""

    def __init__(self, photos, crop, target_mm_per_px, zoom_range, weights=None, paste=None):
        if not photos:
            raise ValueError("no training photos")
        self.photos = photos
        self.crop = tuple(crop)
        self.target_mm_per_px = target_mm_per_px
        self.zoom_range = tuple(zoom_range)
        weights = np.ones(len(photos)) if weights is None else np.asarray(weights, float)
        self.probabilities = weights / weights.sum()
        self.paste_id, self.paste_probability = paste if paste else (None, 0.0)
        self.donors = [p for p in photos if self.paste_probability > 0 and (p.mask == self.paste_id).any()]

    def crop_of(self, rng, photo):
        return random_geometry(rng, photo.image, photo.mask, self.crop, photo.mm_per_px / self.target_mm_per_px,
                               self.zoom_range)

    def pasted(self, rng, image, mask):
        if not self.donors or rng.random() >= self.paste_probability:
            return image, mask
        donor = self.donors[rng.integers(len(self.donors))]
        for _ in range(PASTE_TRIES):
            donor_image, donor_mask = self.crop_of(rng, donor)
            if (donor_mask == self.paste_id).any():
                break
        return paste_class(image, mask, donor_image, donor_mask, self.paste_id)

    def batch(self, rng, size):
        inputs, targets = [], []
        for i in rng.choice(len(self.photos), size=size, replace=True, p=self.probabilities):
            image, mask = self.pasted(rng, *self.crop_of(rng, self.photos[i]))
            inputs.append(normalise(random_photometry(rng, image)))
            targets.append(mask)
        return (torch.from_numpy(np.stack(inputs).astype(np.float32)),
                torch.from_numpy(np.stack(targets).astype(np.int64)))


def class_frequencies(masks, classes):
    """Share of each class among the labelled (not 255) pixels of the masks."""
    counts = np.zeros(classes, np.float64)
    for mask in masks:
        counts += np.bincount(mask[mask != IGNORE].ravel(), minlength=256)[:classes]
    return counts / max(counts.sum(), 1.0)


SHIFT_FACTOR = 2.0
SHIFT_FLOOR = 0.005


def share_shifts(names, training, validation, factor=SHIFT_FACTOR, floor=SHIFT_FLOOR):
    """Classes whose pixel share differs more than factor-fold between the training and the
    validation photos (ignoring classes under floor in both): [(name, training, validation)].
    Such validation photos judge the model on ground unlike what it learnt."""
    shifts = []
    for name, a, b in zip(names, training, validation):
        if max(a, b) < floor:
            continue
        if min(a, b) <= 0 or max(a, b) / min(a, b) > factor:
            shifts.append((name, float(a), float(b)))
    return shifts
