# SPDX-License-Identifier: Apache-2.0
"""tools/train/evaluate.py scores a model as the daemon's pipeline runs it: the same figures
as `weedspray-lab vision-eval --classes` on the same photos. At the photos' own scale the frame
shrinks in both of the daemon's steps (a whole factor, then the rest), so a change to either
side's resampling, blob or class enlargement shows here."""

import json
import os
import subprocess
import tempfile
import unittest

import cv2

import evaluate

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
MODEL = os.path.join(ROOT, "models", "weed-peanut-2mm.onnx")
STEMS = ["0006", "0142", "0201", "0234", "0381"]  # validation photos that share plants with training ones


def peanut_folder():
    data = os.environ.get("WEEDSPRAY_DATA_DIR", "")
    return os.path.join(data, "peanut") if data else ""


@unittest.skipUnless(os.environ.get("WEEDSPRAY_LAB"), "WEEDSPRAY_LAB (the built lab tool) not given")
class DaemonParityTest(unittest.TestCase):
    def test_evaluate_gives_the_lab_tools_figures(self):
        peanut = peanut_folder()
        self.assertTrue(os.path.isdir(os.path.join(peanut, "images")), f"{peanut} (WEEDSPRAY_DATA_DIR)")
        images, masks = os.path.join(peanut, "images"), os.path.join(peanut, "masks")
        with open(MODEL[:-len(".onnx")] + ".json") as text:
            model = json.load(text)
        photo_mm = model["training"]["dataset_mm_per_px"]
        with tempfile.NamedTemporaryFile("w", suffix=".txt") as stems:
            stems.write("\n".join(STEMS) + "\n")
            stems.flush()
            lab = subprocess.run([os.environ["WEEDSPRAY_LAB"], "vision-eval", "--classes", "--json",
                                  "--images", images, "--masks", masks, "--list", stems.name, "--model", MODEL],
                                 capture_output=True, text=True, check=True)
        dnn = next(p for p in json.loads(lab.stdout)["pipelines"] if p["weed_source"] == "dnn")
        net = cv2.dnn.readNetFromONNX(MODEL)
        ours = evaluate.evaluate(net, model["spec"], images, masks, STEMS, photo_mm)
        self.assertGreater(ours["iou"]["weed"], 0.0)
        for name in ("soil", "crop", "weed"):
            self.assertAlmostEqual(ours["iou"][name], dnn["iou"][name], delta=2e-4, msg=name)


if __name__ == "__main__":
    unittest.main()
