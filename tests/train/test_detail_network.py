# SPDX-License-Identifier: Apache-2.0
"""model.SegmentationNet with detail > 1: a fine input, the body on its average, a finer head."""

import unittest

import torch
import torch.nn.functional as F

from loss import loss_fn
from model import SegmentationNet, load_checkpoint_into, stride


def checkpoint_of(model, classes):
    return {"state_dict": model.state_dict(), "classes": classes, "width": 0.5}


class DetailNetwork(unittest.TestCase):
    def test_logits_come_out_at_the_bodys_scale(self):
        for detail in (1, 2, 4):
            model = SegmentationNet(3, detail=detail).eval()
            size = stride(detail) * 2
            with torch.no_grad():
                logits = model(torch.zeros(1, 3, size, size + stride(detail)))
            self.assertEqual(tuple(logits.shape), (1, 3, size // detail, (size + stride(detail)) // detail))

    def test_a_plain_base_gives_the_body_what_it_saw_from_the_averaged_input(self):
        """From a plain network's checkpoint the body starts as that network would on the
        input averaged over the detail factor: the detail branch adds nothing yet."""
        torch.manual_seed(1)
        plain = SegmentationNet(2).eval()
        for module in plain.modules():  # BN statistics other than the defaults
            if isinstance(module, torch.nn.BatchNorm2d):
                module.running_mean.uniform_(-0.5, 0.5)
                module.running_var.uniform_(0.5, 2.0)
        detailed = SegmentationNet(3, detail=2)
        self.assertFalse(load_checkpoint_into(detailed, checkpoint_of(plain, ["soil", "plant"]), ["soil", "crop", "weed"]))
        detailed.eval()
        fine = torch.randn(1, 3, 128, 128)
        seen = {}
        plain.stages[1].register_forward_hook(lambda m, i, o: seen.__setitem__("plain", o))
        detailed.stages[1].register_forward_hook(lambda m, i, o: seen.__setitem__("detailed", o))
        with torch.no_grad():
            plain(F.avg_pool2d(fine, 2))
            detailed(fine)
        self.assertGreater(float(seen["plain"].abs().max()), 0.1)
        self.assertTrue(torch.allclose(seen["plain"], seen["detailed"], atol=1e-5))

    def test_the_detail_branch_learns(self):
        torch.manual_seed(2)
        model = SegmentationNet(3, detail=2).train()
        inputs = torch.randn(2, 3, 64, 64)
        target = torch.randint(0, 3, (2, 64, 64))
        loss = loss_fn(model(inputs), target, torch.ones(3))  # logits 32x32 against a 64x64 mask
        loss.backward()
        self.assertTrue(torch.isfinite(loss))
        self.assertGreater(float(model.detail.weight.grad.abs().sum()), 0.0)
        self.assertGreater(float(model.fine_skip[0].weight.grad.abs().sum()), 0.0)

    def test_a_plain_network_refuses_a_detail_checkpoint(self):
        detailed = SegmentationNet(3, detail=2)
        with self.assertRaisesRegex(ValueError, "does not fit"):
            load_checkpoint_into(SegmentationNet(3), checkpoint_of(detailed, ["soil", "crop", "weed"]),
                                 ["soil", "crop", "weed"])

    def test_only_two_and_four(self):
        with self.assertRaises(ValueError):
            SegmentationNet(3, detail=3)


if __name__ == "__main__":
    unittest.main()
