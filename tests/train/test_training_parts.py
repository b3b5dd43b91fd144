# SPDX-License-Identifier: Apache-2.0
"""tools/train's loss, class weights, sampling, metrics, zones and data-set table."""

import unittest

import cv2
import numpy as np
import torch

from datasets import UNKNOWN_LICENCE, model_licence, plant_soil_mask
from evaluate import (IGNORE, Scores, area_shrink, confusion_matrix, laid_frames, network_input_size, whole_factor,
                      zone_cells, zone_tradeoff)
from loss import auto_class_weights, loss_fn, parse_class_weights
from sampling import Sampler, ScaledPhoto, class_frequencies, paste_class, share_shifts
from synthetic import field_photo
from train import PASTE_PROBABILITY, build_parser, resolve_paste


class ClassWeights(unittest.TestCase):
    def test_auto_weights_lift_a_rare_crop(self):
        mask = np.zeros((100, 100), np.uint8)
        mask[:3, :] = 1  # crop: 3 % of the pixels
        mask[50:51, :50] = 2  # weed: 0.5 %
        frequencies = class_frequencies([mask], 3)
        weights = auto_class_weights(frequencies)
        self.assertEqual(weights[0], 1.0)
        self.assertGreater(weights[1], 4.0)
        self.assertGreater(weights[2], weights[1])
        self.assertTrue(all(1.0 <= w <= 20.0 for w in weights))

    def test_class_without_pixels_gets_the_cap_and_ignore_is_not_counted(self):
        mask = np.full((10, 10), IGNORE, np.uint8)
        mask[:5] = 0
        mask[5, 0] = 1
        frequencies = class_frequencies([mask], 3)
        self.assertAlmostEqual(frequencies.sum(), 1.0)
        self.assertAlmostEqual(frequencies[1], 1 / 51)
        self.assertEqual(auto_class_weights(frequencies)[2], 20.0)

    def test_given_weights_are_checked(self):
        self.assertIsNone(parse_class_weights("auto", 3))
        self.assertEqual(parse_class_weights("1,1.5,4", 3), [1.0, 1.5, 4.0])
        with self.assertRaises(ValueError):
            parse_class_weights("1,2", 3)


class ShareShifts(unittest.TestCase):
    names = ["soil", "crop", "weed"]

    def test_a_crop_four_times_rarer_in_training_is_named(self):
        shifts = share_shifts(self.names, [0.20, 0.023, 0.777], [0.28, 0.098, 0.622])
        self.assertEqual([name for name, _, _ in shifts], ["crop"])
        self.assertAlmostEqual(shifts[0][2], 0.098)

    def test_alike_photos_and_classes_rare_on_both_sides_are_not(self):
        self.assertEqual(share_shifts(self.names, [0.85, 0.12, 0.03], [0.83, 0.138, 0.035]), [])
        self.assertEqual(share_shifts(self.names, [0.996, 0.001, 0.003], [0.99, 0.004, 0.006]), [])

    def test_a_class_missing_from_one_side_is_named(self):
        self.assertEqual([n for n, _, _ in share_shifts(self.names, [0.9, 0.1, 0.0], [0.8, 0.1, 0.1])], ["weed"])


class CropPasting(unittest.TestCase):
    def test_the_donors_class_pixels_are_laid_over_colour_and_label(self):
        image = np.full((4, 6, 3), 10, np.uint8)
        mask = np.full((4, 6), 2, np.uint8)
        mask[0, 0] = IGNORE
        donor_image = np.full((4, 6, 3), 200, np.uint8)
        donor_mask = np.zeros((4, 6), np.uint8)
        donor_mask[1:3, 2:4] = 1
        donor_mask[0, 0] = 2  # another class of the donor's: not pasted
        pasted_image, pasted_mask = paste_class(image, mask, donor_image, donor_mask, 1)
        where = donor_mask == 1
        self.assertTrue((pasted_mask[where] == 1).all())
        self.assertTrue((pasted_image[where] == 200).all())
        self.assertTrue((pasted_mask[~where] == mask[~where]).all())
        self.assertTrue((pasted_image[~where] == 10).all())
        self.assertEqual(int(mask[1, 2]), 2)  # the inputs are left as they were

    def photos(self):
        photos = []
        for seed in range(3):
            image, mask = field_photo(seed)
            mask = mask.copy()
            mask[mask == 1] = 2  # two photos without crop: only the third can give it
            if seed == 2:
                mask[40:48, 60:70] = 1
            photos.append(ScaledPhoto(image, mask, 1.0, 1.0))
        return photos

    def crop_share(self, sampler):
        _, targets = sampler.batch(np.random.default_rng(1), 64)
        return float((targets == 1).float().mean())

    def test_a_rare_crop_is_seen_more_often_and_no_pasting_changes_nothing(self):
        photos = self.photos()
        plain = Sampler(photos, (64, 48), 1.0, (0.9, 1.1))
        pasting = Sampler(photos, (64, 48), 1.0, (0.9, 1.1), paste=(1, 1.0))
        self.assertGreater(self.crop_share(pasting), 2 * self.crop_share(plain))
        off = Sampler(photos, (64, 48), 1.0, (0.9, 1.1), paste=(1, 0.0))
        for a, b in zip(plain.batch(np.random.default_rng(3), 4), off.batch(np.random.default_rng(3), 4)):
            self.assertTrue(torch.equal(a, b))

    def test_auto_pastes_only_a_crop_under_five_per_cent(self):
        args = build_parser().parse_args(["--images", "i", "--masks", "m", "--train-list", "t", "--val-list", "v",
                                          "--out", "o"])
        self.assertEqual(resolve_paste(args, [0.2, 0.023, 0.777])[0], PASTE_PROBABILITY)
        self.assertEqual(resolve_paste(args, [0.85, 0.12, 0.03])[0], 0.0)
        self.assertEqual(resolve_paste(args, [0.9, 0.0, 0.1])[0], 0.0)  # nothing to paste
        args.paste_crop = 0.25
        self.assertEqual(resolve_paste(args, [0.85, 0.12, 0.03]), (0.25, "given"))


class IgnoredPixels(unittest.TestCase):
    def test_loss_does_not_see_ignored_pixels(self):
        torch.manual_seed(0)
        logits = torch.randn(2, 3, 8, 8, requires_grad=True)
        target = torch.randint(0, 3, (2, 8, 8))
        target[:, :4] = IGNORE
        loss = loss_fn(logits, target, torch.tensor([1.0, 2.0, 3.0]))
        loss.backward()
        self.assertTrue(torch.isfinite(loss))
        self.assertEqual(float(logits.grad[:, :, :4].abs().sum()), 0.0)
        changed = logits.detach().clone()
        changed[:, :, :4] += torch.randn(2, 3, 4, 8) * 10
        self.assertAlmostEqual(float(loss_fn(changed, target, torch.tensor([1.0, 2.0, 3.0]))), float(loss), places=5)

    def test_all_ignored_batch_gives_zero_not_nan(self):
        logits = torch.randn(1, 3, 4, 4, requires_grad=True)
        loss = loss_fn(logits, torch.full((1, 4, 4), IGNORE), torch.ones(3))
        loss.backward()
        self.assertEqual(float(loss), 0.0)

    def test_metrics_leave_ignored_pixels_out(self):
        truth = np.array([[0, 1, IGNORE], [2, IGNORE, 1]], np.uint8)
        predicted = np.array([[0, 1, 2], [2, 0, 1]], np.uint8)
        confusion = confusion_matrix(truth, predicted, 3)
        self.assertEqual(int(confusion.sum()), 4)
        self.assertEqual(int(np.trace(confusion)), 4)


class Sampling(unittest.TestCase):
    def test_fewer_photos_than_the_batch(self):
        image, mask = field_photo(0)
        photos = [ScaledPhoto(image, mask, 1.0, 160 / 64)]
        inputs, targets = Sampler(photos, (64, 32), 160 / 64, (0.7, 1.4)).batch(np.random.default_rng(0), 8)
        self.assertEqual(tuple(inputs.shape), (8, 3, 32, 64))
        self.assertEqual(tuple(targets.shape), (8, 32, 64))

    def test_photos_are_cached_at_twice_the_target_resolution_at_most(self):
        image = np.zeros((400, 600, 3), np.uint8)
        mask = np.zeros((400, 600), np.uint8)
        coarse = ScaledPhoto(image, mask, 0.3, 1.2)
        self.assertEqual(coarse.image.shape[:2], (200, 300))
        self.assertAlmostEqual(coarse.mm_per_px, 0.6)
        fine = ScaledPhoto(image, mask, 0.3, 0.4)
        self.assertEqual(fine.image.shape[:2], (400, 600))

    def test_network_input_follows_the_ground_scale_as_the_daemon(self):
        spec = {"input_width": 320, "input_height": 256, "ground_mm_per_px": 0.9375, "stride": 32}
        self.assertEqual(network_input_size(spec, 0.3125, 960, 720), (320, 256))
        self.assertEqual(network_input_size(spec, 0.625, 960, 720), (640, 480))
        self.assertEqual(network_input_size(dict(spec, ground_mm_per_px=None), 0.625, 960, 720), (320, 256))


    def test_frames_shrink_by_a_whole_factor_first_and_keep_their_geometry(self):
        self.assertEqual((whole_factor(1280, 640), whole_factor(800, 384), whole_factor(1280, 400)), (2, 2, 2))
        self.assertEqual((whole_factor(295, 64), whole_factor(221, 64), whole_factor(100, 60)), (1, 1, 1))
        rng = np.random.default_rng(4)
        frame = cv2.GaussianBlur(rng.integers(0, 256, (800, 1280, 3)).astype(np.uint8), (0, 0), 3)
        frame[600:640, 1000:1040] = 255  # a bright square far from the origin
        for size in ((640, 384), (320, 192), (416, 256)):
            shrunk = area_shrink(frame, size)
            direct = cv2.resize(frame, size, interpolation=cv2.INTER_AREA)
            self.assertEqual(shrunk.shape, direct.shape)
            self.assertLess(float(np.abs(shrunk.astype(float) - direct).mean()), 1.5)
            square = [np.argwhere(image[..., 0] > 200).mean(axis=0) for image in (shrunk, direct)]
            self.assertLess(float(np.abs(square[0] - square[1]).max()), 0.15)  # its centre, in output pixels
        halved = cv2.resize(frame, (640, 400), interpolation=cv2.INTER_AREA)  # the rest shrinks by less than half
        self.assertTrue(np.array_equal(area_shrink(frame, (640, 384)),
                                       cv2.resize(halved, (640, 384), interpolation=cv2.INTER_LINEAR)))
        odd = frame[:221, :295]
        self.assertTrue(np.array_equal(area_shrink(odd, (64, 64)), cv2.resize(odd, (64, 64), interpolation=cv2.INTER_AREA)))

    def test_photos_are_laid_into_frames_as_a_camera_sees_the_ground(self):
        pairs = []
        for value in (10, 20, 30):
            image = np.full((40, 60, 3), value, np.uint8)
            mask = np.full((40, 60), value // 10, np.uint8)
            pairs.append((image, mask))
        frames = laid_frames(pairs, 1.0, 2.0, (50, 30))  # photos become 30 x 20
        self.assertEqual(len(frames), 1)
        frame, truth = frames[0]
        self.assertEqual(frame.shape, (30, 50, 3))
        self.assertEqual((frame[0, 0, 0], frame[0, 45, 0], frame[25, 0, 0], frame[25, 45, 0]), (10, 20, 30, 10))
        self.assertEqual((truth[0, 0], truth[0, 45], truth[25, 0], truth[25, 45]), (1, 2, 3, 1))
        self.assertTrue(np.array_equal(truth, frame[..., 0] // 10))

class Zones(unittest.TestCase):
    def test_zone_kinds_and_the_farmers_rule(self):
        truth = np.zeros((20, 40), np.uint8)  # 2 x 4 zones of 10 x 10
        truth[0:2, 0:2] = 2  # zone 0 weedy (4 %)
        truth[0:3, 10:13] = 1  # zone 1 crop only
        truth[10:20, 30:40] = IGNORE  # zone 7 not counted
        predicted = np.zeros_like(truth)
        predicted[0:2, 0:2] = 2
        predicted[0:1, 10:11] = 2  # 1 % weed called in the crop-only zone
        cells = zone_cells(truth, predicted, crop_class=1, weed_class=2)
        zones = zone_tradeoff(cells)
        self.assertEqual((zones["weedy"], zones["crop_only"], zones["bare"], zones["not_counted"]), (1, 1, 5, 1))
        by_threshold = {row["threshold"]: row for row in zones["thresholds"]}
        self.assertEqual(by_threshold[0.005]["crop_only_left_dry"], 0.0)
        self.assertEqual(by_threshold[0.02]["crop_only_left_dry"], 1.0)
        self.assertEqual(zones["best"]["threshold"], 0.02)
        self.assertEqual(zones["best"]["recall"], 1.0)

    def test_per_image_scores_and_intervals(self):
        scores = Scores(["soil", "crop", "weed"], 1, 2)
        for seed in range(4):
            _, truth = field_photo(seed, 80, 64)
            predicted = truth.copy()
            predicted[:, : 10 * seed] = 0
            scores.add(f"p{seed}", truth, predicted)
        summary = scores.summary()
        self.assertEqual([row["image"] for row in summary["per_image"]], ["p0", "p1", "p2", "p3"])
        self.assertEqual(summary["per_image"][0]["iou"]["crop"], 1.0)
        low, high = summary["intervals"]["iou"]["crop"]
        self.assertLessEqual(low, summary["iou"]["crop"])
        self.assertGreaterEqual(high, summary["iou"]["crop"])
        self.assertIn("crop_only_left_dry", summary["intervals"]["zones"])


class DataSets(unittest.TestCase):
    def test_crop_only_labels_ignore_green_soil(self):
        image, mask = field_photo(3)
        crop_only = np.where(mask == 1, 1, 0).astype(np.uint8)
        entry = {"plant_soil": {"0": "soil", "1": "plant"}, "green_unlabelled_is_ignore": True}
        out = plant_soil_mask(entry, image, crop_only)
        self.assertTrue(np.all(out[mask == 1] == 1))
        self.assertGreater(float(np.mean(out[mask == 2] == IGNORE)), 0.9)
        self.assertGreater(float(np.mean(out[mask == 0] == 0)), 0.6)

    def test_licence_follows_share_alike_data(self):
        records = [{"images": "../shared/data/peanut", "licence": "CC BY-SA 4.0"},
                   {"images": "/home/me/photos", "licence": UNKNOWN_LICENCE}]
        self.assertTrue(model_licence(records).startswith("CC BY-SA 4.0"))
        self.assertIn(UNKNOWN_LICENCE, model_licence(records))
        self.assertEqual(model_licence([{"images": "x", "licence": "MIT"}]), "MIT (x)")


if __name__ == "__main__":
    unittest.main()
