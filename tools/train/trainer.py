# SPDX-License-Identifier: Apache-2.0
"""The optimisation loop train.py and train_base.py share, and a quick torch-side IoU.

AdamW (weight decay 1e-4) with a linear warm-up over the first 1/30 of the steps and a cosine
decay to zero; one step = one batch drawn by a sampling.Sampler. Every log_every steps a line
with the mean loss, steps/s (time in validation left out) and the time left; every val_every
steps (and at the end) the caller's validate(model) adds its figures to the line.
"""

import time

import cv2
import numpy as np
import torch

from evaluate import IGNORE, network_input_size, to_blob
from loss import loss_fn


def learning_rate(step, total, peak):
    warmup = max(1, total // 30)
    if step < warmup:
        return peak * (step + 1) / warmup
    return 0.5 * peak * (1 + np.cos(np.pi * (step - warmup) / max(1, total - warmup)))


def format_seconds(seconds):
    seconds = int(round(seconds))
    return f"{seconds // 60} min {seconds % 60:02d} s" if seconds >= 60 else f"{seconds} s"


def train_steps(model, sampler, steps, batch, lr, class_weights, rng, log_every=25, validate=None, val_every=0):
    """Runs steps optimiser steps; returns {"wall_s", "train_s", "steps_per_s", "last_loss"}."""
    optimiser = torch.optim.AdamW(model.parameters(), lr=lr, weight_decay=1e-4)
    weights = torch.tensor(class_weights, dtype=torch.float32)
    started = time.time()
    validation_s = 0.0
    running = []
    model.train()
    for step in range(steps):
        for group in optimiser.param_groups:
            group["lr"] = learning_rate(step, steps, lr)
        inputs, targets = sampler.batch(rng, batch)
        loss = loss_fn(model(inputs), targets, weights)
        optimiser.zero_grad()
        loss.backward()
        optimiser.step()
        running.append(loss.item())
        done = step + 1
        if done % log_every and done != steps:
            continue
        rate = done / max(time.time() - started - validation_s, 1e-6)
        line = (f"step {done}/{steps} loss {np.mean(running):.4f} {rate:.2f} steps/s, "
                f"{format_seconds(time.time() - started)} so far, ~{format_seconds((steps - done) / rate)} left")
        last_loss = float(np.mean(running))
        running = []
        if validate and (done == steps or (val_every and done % val_every == 0)):
            checked = time.time()
            line += " | " + validate(model)
            model.train()
            validation_s += time.time() - checked
        print(line, flush=True)
    wall_s = time.time() - started
    return {"wall_s": round(wall_s, 1), "train_s": round(wall_s - validation_s, 1),
            "steps_per_s": round(steps / max(wall_s - validation_s, 1e-6), 3), "last_loss": round(last_loss, 4)}


def quick_iou(model, samples, spec):
    """IoU per class with torch at the network's output resolution over (image, mask, photo mm/px or
    None) samples, unlabelled pixels left out (progress lines and the base's figures)."""
    classes = len(spec["classes"])
    confusion = np.zeros((classes, classes), np.int64)
    model.eval()
    with torch.no_grad():
        for image, mask, mm_per_px in samples:
            size = network_input_size(spec, mm_per_px, image.shape[1], image.shape[0])
            labels = model(torch.from_numpy(to_blob(image, spec, size)))[0].argmax(0).numpy()
            small = cv2.resize(mask, labels.shape[::-1], interpolation=cv2.INTER_NEAREST)
            labelled = small != IGNORE
            index = small[labelled].astype(np.int64) * classes + labels[labelled]
            confusion += np.bincount(index, minlength=classes**2).reshape(classes, classes)
    tp = np.diag(confusion)
    return tp / np.maximum(confusion.sum(0) + confusion.sum(1) - tp, 1)
