#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""Makes tests/data/tiny-3class.onnx: a few-hundred-byte 3-class segmentation net for C++ tests.

Not trained: the weights are set by hand so that its answer is known. Class k's logit is the
3x3 mean of input channel k (after the caller's mean/scale and channel order), so with
mean 0, scale 1/255 and RGB order a red pixel is class 0, green class 1, blue class 2; feed
BGR by mistake and red comes out as class 2. It uses the ops of the shipped model (Conv with
stride 2, depthwise Conv, BatchNorm folded into Conv, ReLU, bilinear Resize x2), takes
1 x 3 x H x W with H and W multiples of 2 (exported at 64 x 64) and returns 1 x 3 x H x W logits.

    /usr/bin/python3 tools/train/make_tiny_onnx.py [--out tests/data/tiny-3class.onnx]
"""

import argparse
import os
import sys

import torch
from torch import nn

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from onnx_export import export_onnx, max_abs_diff_vs_opencv  # noqa: E402

HIDDEN = 4  # channels 0-2 carry R, G, B; channel 3 is an unused zero channel


class TinyThreeClass(nn.Module):
    def __init__(self):
        super().__init__()
        self.down = nn.Conv2d(3, HIDDEN, 3, stride=2, padding=1, bias=False)
        self.depthwise = nn.Conv2d(HIDDEN, HIDDEN, 3, padding=1, groups=HIDDEN, bias=False)
        self.norm = nn.BatchNorm2d(HIDDEN)
        self.relu = nn.ReLU()
        self.classify = nn.Conv2d(HIDDEN, 3, 1)
        self.up = nn.Upsample(scale_factor=2, mode="bilinear", align_corners=False)
        with torch.no_grad():
            self.down.weight.zero_()
            for c in range(3):
                self.down.weight[c, c] = 1.0 / 9.0
            self.depthwise.weight.zero_()
            self.depthwise.weight[:, 0, 1, 1] = 1.0
            self.classify.weight.zero_()
            self.classify.bias.zero_()
            for k in range(3):
                self.classify.weight[k, k, 0, 0] = 1.0

    def forward(self, x):
        return self.up(self.classify(self.relu(self.norm(self.depthwise(self.down(x))))))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    parser.add_argument("--out", default=os.path.join(root, "tests", "data", "tiny-3class.onnx"))
    args = parser.parse_args()
    model = TinyThreeClass().eval()
    os.makedirs(os.path.dirname(args.out), exist_ok=True)
    export_onnx(model, args.out, 64, 64)
    torch.manual_seed(0)
    diff = max_abs_diff_vs_opencv(model, args.out, [torch.rand(1, 3, 64, 64), torch.rand(1, 3, 96, 128)])
    if diff > 1e-5:
        raise SystemExit(f"{args.out}: OpenCV DNN differs from torch by {diff}")
    print(f"{args.out}: {os.path.getsize(args.out)} bytes, OpenCV vs torch max abs diff {diff:.2e}")


if __name__ == "__main__":
    main()
