# SPDX-License-Identifier: Apache-2.0
"""tools/train/train.py and train_base.py end to end on a few tiny synthetic photos (seconds)."""

import contextlib
import io
import json
import os
import subprocess
import tempfile
import unittest
import unittest.mock

import cv2
import numpy as np

import train
import train_base
from synthetic import write_field, write_list

TRAIN = ["a", "b", "c"]
VAL = ["d", "e"]


def run(main, argv):
    with contextlib.redirect_stdout(io.StringIO()) as printed:
        main(argv)
    return printed.getvalue()


class SmallSetTraining(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory()
        root = cls.tmp.name
        # Every mask has an unlabelled (255) corner: loss and figures must leave it out.
        cls.images, cls.masks = write_field(os.path.join(root, "field"), TRAIN + VAL, ignore_box=(0, 0, 40, 30))
        cls.train_list = write_list(os.path.join(root, "train.txt"), TRAIN)
        cls.val_list = write_list(os.path.join(root, "val.txt"), VAL)
        cls.out = os.path.join(root, "out")
        cls.etc = os.path.join(root, "etc")
        cls.log = run(train.main, cls.common("tiny") + [
            "--steps", "3", "--dataset-mm-per-px", "1.0", "--report-worst", "2",
            "--data-licence", "own photos, CC0", "--install", cls.etc])
        with open(os.path.join(cls.out, "tiny.json")) as text:
            cls.report = json.load(text)

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    @classmethod
    def common(cls, name):
        return ["--images", cls.images, "--masks", cls.masks, "--train-list", cls.train_list,
                "--val-list", cls.val_list, "--out", cls.out, "--name", name, "--batch", "8",
                "--input", "64x64", "--crop", "64x64", "--log-every", "1", "--threads", "2"]

    def test_onnx_runs_in_opencv(self):
        net = cv2.dnn.readNet(os.path.join(self.out, "tiny.onnx"))
        net.setInput(np.zeros((1, 3, 64, 64), np.float32))
        self.assertEqual(net.forward().shape, (1, 3, 64, 64))

    def test_spec_records_the_ground_scale(self):
        spec = self.report["spec"]
        self.assertAlmostEqual(spec["ground_mm_per_px"], 160 / 64)
        self.assertEqual((spec["stride"], spec["input_channels"]), (32, 3))
        self.assertEqual(spec["classes"], ["soil", "crop", "weed"])

    def test_validation_figures(self):
        validation = self.report["validation"]
        self.assertEqual(set(validation["iou"]), {"soil", "crop", "weed"})
        self.assertIn("miou", validation)
        self.assertIn("crop_only_left_dry", validation["zones"]["best"])
        for row in validation["zones"]["thresholds"]:
            self.assertEqual(set(row), {"threshold", "recall", "crop_only_left_dry", "bare_left_dry", "clean_left_dry"})
        self.assertEqual([row["image"] for row in validation["per_image"]], VAL)
        self.assertIn("weed", validation["intervals"]["iou"])
        self.assertEqual(validation["zones"]["not_counted"], 0)
        for limit in ("true_outline", "true_classes"):
            self.assertEqual(set(validation["limits"][limit]["iou"]), {"soil", "crop", "weed"})
        self.assertEqual(validation["limits"]["true_outline"]["iou"]["soil"], 1.0)  # the labels' soil, exactly
        self.assertIn("with the labels' plant outline", self.log)

    def test_steps_log_and_training_record(self):
        self.assertIn("steps/s", self.log)
        self.assertIn("left", self.log)
        training = self.report["training"]
        self.assertEqual((training["steps"], training["batch"], training["train_images"]), (3, 8, 3))
        self.assertEqual(len(training["class_weights"]), 3)
        for key in ("class_shares", "validation_class_shares"):
            self.assertEqual(set(training[key]), {"soil", "crop", "weed"})
            self.assertAlmostEqual(sum(training[key].values()), 1.0, places=3)
        self.assertIn("validation class shares soil", self.log)
        self.assertTrue(0 <= training["paste_crop"]["probability"] <= 1)
        for key in ("spec", "validation", "training_set", "export", "inference", "training", "licence"):
            self.assertIn(key, self.report)

    def test_training_data_and_licence(self):
        data = self.report["training_data"]
        self.assertEqual(data[0]["count"], 3)
        self.assertEqual(data[0]["licence"], "own photos, CC0")
        self.assertIn("own photos, CC0", self.report["licence"])

    def test_the_plant_soil_base_is_the_default(self):
        """Without --base the run starts from models/base-plant-soil.pt and carries its data."""
        self.assertEqual(self.report["training"]["base"]["path"], train.DEFAULT_BASE)
        self.assertEqual(self.report["training"]["base"]["classes"], ["soil", "plant"])
        self.assertIn("--base " + train.DEFAULT_BASE, self.log)
        self.assertEqual(sorted(d["via"] for d in self.report["training_data"][1:]),
                         ["base base-plant-soil.pt"] * 3)
        self.assertTrue(self.report["licence"].startswith("CC BY-SA 4.0"))
        self.assertIsNone(train.parse_args(self.common("scratch") + ["--base", "none"]).base)
        with unittest.mock.patch.object(train, "DEFAULT_BASE", os.path.join(self.tmp.name, "missing.pt")):
            with contextlib.redirect_stdout(io.StringIO()) as printed:
                self.assertIsNone(train.parse_args(self.common("scratch")).base)
        self.assertIn("training from scratch", printed.getvalue())

    def test_report_overlays(self):
        folder = os.path.join(self.out, "tiny-report")
        self.assertEqual(len(self.report["report"]["worst"]), 2)
        for name in self.report["report"]["worst"]:
            self.assertIsNotNone(cv2.imread(os.path.join(folder, name)))

    def test_install(self):
        self.assertTrue(os.path.exists(os.path.join(self.etc, "tiny.onnx")))
        self.assertTrue(os.path.exists(os.path.join(self.etc, "tiny.json")))
        with open(os.path.join(self.etc, "conf.d", "50-model-tiny.toml")) as text:
            drop_in = text.read()
        self.assertIn('[vision]\nweed_source = "dnn"\n', drop_in)
        self.assertIn(f'model = "{os.path.join(os.path.abspath(self.etc), "tiny.onnx")}"', drop_in)

    @unittest.skipUnless(os.environ.get("WEEDSPRAYD"), "WEEDSPRAYD (the built daemon) not given")
    def test_the_daemon_accepts_the_installed_model(self):
        """The JSON train.py writes is the spec the daemon reads: --check-config loads the
        installed model through the drop-in and says how the default camera meets it."""
        main = os.path.join(self.etc, "weedspray.toml")
        with open(main, "w") as out:
            out.write("# the defaults\n")
        # --sim: the defaults wire no heartbeat, which hardware mode requires.
        checked = subprocess.run([os.environ["WEEDSPRAYD"], "--sim", "--check-config",
                                  "--config", main],
                                 capture_output=True, text=True)
        self.assertEqual(checked.returncode, 0, checked.stderr)
        self.assertIn("configuration OK", checked.stdout)
        self.assertRegex(checked.stdout, r"camera\[0\]: 1.01 mm/px -> tiny.onnx "
                                         r"\(learnt at [0-9.]+ mm/px; .*\): network input \d+x\d+\n")

    def test_detail_network_end_to_end(self):
        """--detail 2: a stride-64 spec whose logits are half the input's size, exported for
        OpenCV and accepted by the daemon; sizes that are no multiple of 64 are refused."""
        etc = os.path.join(self.tmp.name, "etc-detail")
        run(train.main, self.common("fine") + [
            "--steps", "2", "--detail", "2", "--input", "128x128", "--crop", "128x64",
            "--dataset-mm-per-px", "1.0", "--target-mm-per-px", "1.0", "--report-worst", "0", "--install", etc])
        with open(os.path.join(self.out, "fine.json")) as text:
            report = json.load(text)
        self.assertEqual((report["spec"]["stride"], report["training"]["detail"]), (64, 2))
        self.assertIn("input_height/2 x input_width/2", report["spec"]["output"])
        self.assertIn("weed", report["validation"]["iou"])
        net = cv2.dnn.readNet(os.path.join(self.out, "fine.onnx"))
        net.setInput(np.zeros((1, 3, 128, 192), np.float32))
        self.assertEqual(net.forward().shape, (1, 3, 64, 96))
        with self.assertRaises(SystemExit), contextlib.redirect_stderr(io.StringIO()) as refused:
            train.parse_args(self.common("odd") + ["--detail", "2", "--crop", "96x64"])
        self.assertIn("--crop 96x64: with --detail 2 the sides must be multiples of 64", refused.getvalue())
        if os.environ.get("WEEDSPRAYD"):
            main = os.path.join(etc, "weedspray.toml")
            with open(main, "w") as out:
                out.write("# the defaults\n")
            checked = subprocess.run([os.environ["WEEDSPRAYD"], "--sim", "--check-config", "--config", main],
                                     capture_output=True, text=True)
            self.assertEqual(checked.returncode, 0, checked.stderr)
            self.assertIn("fine.onnx", checked.stdout)

    def test_epochs_without_scale_from_a_checkpoint(self):
        log = run(train.main, self.common("again") + [
            "--epochs", "1", "--base", os.path.join(self.out, "tiny.pt"), "--report-worst", "0"])
        self.assertIn("--dataset-mm-per-px not given", log)
        self.assertIn("class head kept", log)
        with open(os.path.join(self.out, "again.json")) as text:
            report = json.load(text)
        self.assertIsNone(report["spec"]["ground_mm_per_px"])
        self.assertEqual(report["training"]["steps"], 1)

    def test_base_then_fine_tune(self):
        root = self.tmp.name
        crop_only = os.path.join(root, "crop-only")
        images, masks = write_field(crop_only, ["x", "y", "z"])
        for stem in ("x", "y", "z"):
            path = os.path.join(masks, stem + ".png")
            cv2.imwrite(path, (cv2.imread(path, cv2.IMREAD_UNCHANGED) == 1).astype(np.uint8))
        table = os.path.join(root, "datasets.json")
        entries = [
            {"name": "field", "path": os.path.join(root, "field"), "images": "images", "masks": "masks",
             "mm_per_px": 1.0, "mm_per_px_estimate": "synthetic", "licence": "CC BY-SA 4.0", "attribution": "test",
             "plant_soil": {"0": "soil", "1": "plant", "2": "plant", "255": "ignore"},
             "green_unlabelled_is_ignore": False},
            {"name": "crop-only", "path": crop_only, "images": "images", "masks": "masks",
             "mm_per_px": 2.0, "mm_per_px_estimate": "synthetic", "licence": "MIT", "attribution": "test",
             "plant_soil": {"0": "soil", "1": "plant"}, "green_unlabelled_is_ignore": True},
        ]
        with open(table, "w") as out:
            json.dump({"datasets": entries}, out)
        base_dir = os.path.join(root, "base")
        run(train_base.main, ["--out", base_dir, "--name", "base", "--steps", "2", "--table", table,
                              "--crop", "64x64", "--val-per-dataset", "1", "--target-mm-per-px", "2.5"])
        with open(os.path.join(base_dir, "base.json")) as text:
            base = json.load(text)
        self.assertEqual(base["classes"], ["soil", "plant"])
        self.assertEqual([d["count"] for d in base["training_data"]], [4, 2])
        self.assertTrue(base["licence"].startswith("CC BY-SA 4.0"))
        log = run(train.main, self.common("tuned") + [
            "--steps", "2", "--dataset-mm-per-px", "1.0", "--base", os.path.join(base_dir, "base.pt"),
            "--report-worst", "0"])
        self.assertIn("class head new", log)
        with open(os.path.join(self.out, "tuned.json")) as text:
            tuned = json.load(text)
        self.assertEqual(len(tuned["training_data"]), 3)
        self.assertEqual(tuned["training_data"][1]["via"], "base base.pt")


if __name__ == "__main__":
    unittest.main()
