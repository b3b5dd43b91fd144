# SPDX-License-Identifier: Apache-2.0
"""The crop/weed/soil segmentation network: MobileNetV2 (width 0.5) encoder, light U-Net decoder.

Encoder: torchvision mobilenet_v2(weights=None, width_mult=0.5).features[0:18] (down to /32,
no 1280-channel head), ReLU6 replaced by ReLU (OpenCV 4.6 cannot load the Clip ReLU6 exports as).
Decoder: at /16, /8, /4, /2 a bilinear x2 upsampling, concatenation with the encoder's skip and
a depthwise-separable block (3x3 depthwise + 1x1 pointwise, BN, ReLU); a 1x1 classifier and a
last bilinear x2 give logits at the input size. About 0.5 M parameters, 2 MB as ONNX.
Input sizes must be multiples of 32.

With detail = K > 1 (2 or 4) the input is K times finer than the network above sees it: the
encoder gets the input averaged over K x K (what the daemon's area resampling would give at K
times the scale), a K*2 x K*2 stride-K*2 convolution of the fine input adds to its first layer
what the averaging lost (zero at the start, so a base's weights work unchanged), and one more
decoder stage at the averaged scale, fed by a stride-K convolution of the fine input, gives the
logits there: 1/K of the input's size, twice as fine as the plain network decides (its class
head works at half its input's resolution). Input sizes must be multiples of 32 * K
(``stride``). For a camera finer than the network's body, at a few ms more a frame than the
plain network.

Checkpoints (NAME.pt, torch.save of a dict): state_dict, classes, width and meta (ground scale,
training data, licence: what a model built on it must carry on). load_checkpoint_into copies a
checkpoint's encoder and decoder into a network with other classes and starts its 1x1 class
head afresh (kept when the class names are the same).
"""

import torch
from torch import nn
from torchvision.models import mobilenet_v2

# Encoder stages whose outputs feed the decoder: /2, /4, /8, /16 (skips) and /32 (bottom).
SKIP_ENDS = (2, 4, 7, 14)
ENCODER_END = 18
DECODER_CHANNELS = (64, 32, 24, 16)
HEAD_PREFIX = "classify."
DETAIL_PREFIXES = ("detail.", "fine_skip.", "fine_block.")
FINE_CHANNELS = 8


def _relu6_to_relu(module: nn.Module) -> None:
    for name, child in module.named_children():
        if isinstance(child, nn.ReLU6):
            setattr(module, name, nn.ReLU(inplace=True))
        else:
            _relu6_to_relu(child)


class SeparableBlock(nn.Sequential):
    def __init__(self, in_channels: int, out_channels: int):
        super().__init__(
            nn.Conv2d(in_channels, in_channels, 3, padding=1, groups=in_channels, bias=False),
            nn.BatchNorm2d(in_channels),
            nn.ReLU(inplace=True),
            nn.Conv2d(in_channels, out_channels, 1, bias=False),
            nn.BatchNorm2d(out_channels),
            nn.ReLU(inplace=True),
        )


def stride(detail: int = 1) -> int:
    """What the input's sides must be multiples of."""
    return 32 * detail


class SegmentationNet(nn.Module):
    def __init__(self, classes: int, width: float = 0.5, detail: int = 1):
        super().__init__()
        if detail not in (1, 2, 4):
            raise ValueError(f"detail {detail}: must be 1, 2 or 4")
        self.detail_factor = detail
        features = mobilenet_v2(weights=None, width_mult=width).features[:ENCODER_END]
        _relu6_to_relu(features)
        bounds = (0,) + SKIP_ENDS + (ENCODER_END,)
        self.stages = nn.ModuleList(features[a:b] for a, b in zip(bounds[:-1], bounds[1:]))
        with torch.no_grad():
            probe = torch.zeros(1, 3, 64, 64)
            channels = []
            for stage in self.stages:
                probe = stage(probe)
                channels.append(probe.shape[1])
        skip_channels = channels[:-1][::-1]  # /16, /8, /4, /2
        below = channels[-1]
        blocks = []
        for skip, out in zip(skip_channels, DECODER_CHANNELS):
            blocks.append(SeparableBlock(below + skip, out))
            below = out
        self.decoder = nn.ModuleList(blocks)
        self.up = nn.Upsample(scale_factor=2, mode="bilinear", align_corners=False)
        if detail == 1:
            self.classify = nn.Conv2d(below, classes, 1)
            return
        self.pool = nn.AvgPool2d(detail)
        first = self.stages[0][0][0]
        self.detail = nn.Conv2d(3, first.out_channels, 2 * detail, stride=2 * detail, bias=False)
        nn.init.zeros_(self.detail.weight)
        self.fine_skip = _conv_bn_relu(nn.Conv2d(3, FINE_CHANNELS, detail, stride=detail, bias=False))
        self.fine_block = _conv_bn_relu(nn.Conv2d(below + FINE_CHANNELS, FINE_CHANNELS, 1, bias=False))
        self.classify = nn.Conv2d(FINE_CHANNELS, classes, 1)

    def forward(self, x):
        fine = x
        stages = iter(self.stages)
        skips = []
        if self.detail_factor > 1:
            # The first stage's convolution, BN and ReLU, with the detail branch added before BN.
            first = next(stages)
            x = first[1:](first[0][2](first[0][1](first[0][0](self.pool(fine)) + self.detail(fine))))
            skips.append(x)
        for stage in stages:
            x = stage(x)
            skips.append(x)
        x = skips.pop()
        for block in self.decoder:
            x = block(torch.cat([self.up(x), skips.pop()], dim=1))
        if self.detail_factor == 1:
            return self.up(self.classify(x))
        return self.classify(self.fine_block(torch.cat([self.up(x), self.fine_skip(fine)], dim=1)))


def _conv_bn_relu(conv: nn.Conv2d) -> nn.Sequential:
    return nn.Sequential(conv, nn.BatchNorm2d(conv.out_channels), nn.ReLU(inplace=True))


def save_checkpoint(path: str, model: SegmentationNet, classes, meta: dict, width: float = 0.5) -> None:
    torch.save({"state_dict": model.state_dict(), "classes": list(classes), "width": width,
                "detail": model.detail_factor, "meta": meta}, path)


def read_checkpoint(path: str) -> dict:
    try:
        checkpoint = torch.load(path, map_location="cpu")
    except (OSError, RuntimeError) as error:
        raise ValueError(f"{path}: cannot read a checkpoint ({error})")
    if not isinstance(checkpoint, dict) or "state_dict" not in checkpoint or "classes" not in checkpoint:
        raise ValueError(f"{path}: not a checkpoint of train.py or train_base.py (no state_dict/classes)")
    return checkpoint


def load_checkpoint_into(model: SegmentationNet, checkpoint: dict, classes) -> bool:
    """Copies the checkpoint's weights into model; True when the class head was kept too.
    A checkpoint without the detail parts (a plain network's) leaves them as they start."""
    own = model.state_dict()
    keep_head = list(checkpoint["classes"]) == list(classes) and all(
        v.shape == own[k].shape for k, v in checkpoint["state_dict"].items() if k.startswith(HEAD_PREFIX) and k in own)
    weights = {k: v for k, v in checkpoint["state_dict"].items() if keep_head or not k.startswith(HEAD_PREFIX)}
    try:
        missing, unexpected = model.load_state_dict(weights, strict=False)
    except RuntimeError as error:
        raise ValueError(f"checkpoint does not fit the network (width {checkpoint.get('width')}): {error}")
    brought_detail = any(k.startswith(DETAIL_PREFIXES) for k in weights)
    body_missing = [k for k in missing
                    if not k.startswith(HEAD_PREFIX) and (brought_detail or not k.startswith(DETAIL_PREFIXES))]
    if body_missing or unexpected:
        raise ValueError(f"checkpoint does not fit the network (width {checkpoint.get('width')}): "
                         f"missing {body_missing[:3]}, unexpected {unexpected[:3]}")
    return keep_head
