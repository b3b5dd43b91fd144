# SPDX-License-Identifier: Apache-2.0
"""ONNX export that OpenCV 4.6 DNN loads, and a check of the file against torch.

OpenCV 4.6 pitfalls handled here (see ../shared/notes/dnn.md):
- ReLU6 exports as a 3-input Clip, which OpenCV 4.6 rejects: models here use ReLU only,
  and export refuses a model that still has ReLU6.
- torch 1.13 may turn identical initialisers into Identity nodes, which OpenCV 4.6 rejects:
  each Identity fed by an initialiser becomes an initialiser of its own.
- PixelShuffle exports as DepthToSpace, which OpenCV 4.6 imports as Reshapes fixed to the
  export's input size: the daemon feeds the size its camera and ground scale give, and such a
  network fails there. Export refuses it (a ConvTranspose2d of kernel and stride K computes the
  same sub-pixel layer and runs at any size).
- opset 11 with bilinear Resize at constant scales loads fine.
"""

import cv2
import numpy as np
import onnx
import torch
from torch import nn

OPSET = 11
INPUT_NAME = "input"
OUTPUT_NAME = "logits"


def export_onnx(model: nn.Module, path: str, width: int, height: int) -> None:
    """Writes model (N x 3 x H x W in, N x C x H x W logits out) as ONNX for OpenCV 4.6."""
    if any(isinstance(m, nn.ReLU6) for m in model.modules()):
        raise ValueError("export_onnx: model has ReLU6 (exports as a Clip OpenCV 4.6 rejects)")
    if any(isinstance(m, nn.PixelShuffle) for m in model.modules()):
        raise ValueError("export_onnx: model has PixelShuffle (OpenCV 4.6 runs its DepthToSpace only at the "
                         "export's input size; use ConvTranspose2d with kernel = stride)")
    model = model.eval()
    dummy = torch.zeros(1, 3, height, width)
    torch.onnx.export(
        model,
        dummy,
        path,
        opset_version=OPSET,
        input_names=[INPUT_NAME],
        output_names=[OUTPUT_NAME],
        do_constant_folding=True,
    )
    graph_model = onnx.load(path)
    _inline_identity_initialisers(graph_model.graph)
    onnx.checker.check_model(graph_model)
    onnx.save(graph_model, path)


def _inline_identity_initialisers(graph: onnx.GraphProto) -> None:
    initialisers = {init.name: init for init in graph.initializer}
    kept = []
    for node in graph.node:
        if node.op_type == "Identity" and node.input[0] in initialisers:
            copy = onnx.TensorProto()
            copy.CopyFrom(initialisers[node.input[0]])
            copy.name = node.output[0]
            graph.initializer.append(copy)
            initialisers[copy.name] = copy
        else:
            kept.append(node)
    del graph.node[:]
    graph.node.extend(kept)


def load_opencv_net(path: str) -> cv2.dnn.Net:
    net = cv2.dnn.readNet(path)
    net.setPreferableBackend(cv2.dnn.DNN_BACKEND_OPENCV)
    net.setPreferableTarget(cv2.dnn.DNN_TARGET_CPU)
    return net


def max_abs_diff_vs_opencv(model: nn.Module, path: str, batches: list) -> float:
    """Largest |torch - OpenCV DNN| over the given 1 x 3 x H x W float tensors."""
    net = load_opencv_net(path)
    model = model.eval()
    worst = 0.0
    with torch.no_grad():
        for tensor in batches:
            expected = model(tensor).numpy()
            net.setInput(np.ascontiguousarray(tensor.numpy(), dtype=np.float32))
            got = net.forward()
            if got.shape != expected.shape:
                raise RuntimeError(f"OpenCV output shape {got.shape} != torch {expected.shape}")
            worst = max(worst, float(np.abs(got - expected).max()))
    return worst
