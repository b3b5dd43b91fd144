# SPDX-License-Identifier: Apache-2.0
"""onnx_export: what OpenCV 4.6 DNN loads and runs at the sizes the daemon feeds."""

import os
import tempfile
import unittest

import torch
from torch import nn

from model import SegmentationNet
from onnx_export import export_onnx, max_abs_diff_vs_opencv


class OnnxExport(unittest.TestCase):
    def setUp(self):
        self.folder = tempfile.TemporaryDirectory()
        self.path = os.path.join(self.folder.name, "m.onnx")

    def tearDown(self):
        self.folder.cleanup()

    def test_a_detail_network_runs_at_sizes_other_than_its_exports(self):
        """The daemon sizes the input from its frame and ground scale, not from the export."""
        torch.manual_seed(4)
        model = SegmentationNet(3, detail=2).eval()
        export_onnx(model, self.path, 128, 128)
        inputs = [torch.randn(1, 3, 128, 128), torch.randn(1, 3, 192, 320), torch.randn(1, 3, 64, 128)]
        self.assertLess(max_abs_diff_vs_opencv(model, self.path, inputs), 1e-4)

    def test_refuses_relu6(self):
        with self.assertRaisesRegex(ValueError, "ReLU6"):
            export_onnx(nn.Sequential(nn.Conv2d(3, 3, 1), nn.ReLU6()), self.path, 64, 64)

    def test_refuses_pixel_shuffle(self):
        with self.assertRaisesRegex(ValueError, "PixelShuffle"):
            export_onnx(nn.Sequential(nn.Conv2d(3, 12, 1), nn.PixelShuffle(2)), self.path, 64, 64)


if __name__ == "__main__":
    unittest.main()
