# SPDX-License-Identifier: Apache-2.0
"""tools/train/labels.py and import_labels.py: every export format to class-id masks."""

import base64
import contextlib
import io
import json
import os
import tempfile
import unittest
import zipfile

import cv2
import numpy as np
from PIL import Image

import import_labels
from labels import (IGNORE, LabelError, LabelMapping, import_source, parse_map, rle_counts_from_string)

CLASSES = ("soil", "crop", "weed")


def mapping(text="", unlabelled="soil"):
    return LabelMapping(CLASSES, parse_map(text), unlabelled)


def read_mask(folder, stem):
    return cv2.imread(os.path.join(folder, stem + ".png"), cv2.IMREAD_UNCHANGED)


def rle_counts_to_string(counts):
    """pycocotools' rleToString, to make a compressed RLE the importer must read back."""
    text = []
    for i, value in enumerate(counts):
        if i > 2:
            value -= counts[i - 2]
        more = True
        while more:
            chunk = value & 0x1F
            value >>= 5
            more = value != -1 if chunk & 0x10 else value != 0
            if more:
                chunk |= 0x20
            text.append(chr(chunk + 48))
    return "".join(text)


def rle_counts(mask):
    flat = mask.T.ravel().astype(bool)
    counts, value, run = [], False, 0
    for pixel in flat:
        if pixel != value:
            counts.append(run)
            value, run = pixel, 0
        run += 1
    counts.append(run)
    return counts


class LabelImport(unittest.TestCase):
    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.dir = self.tmp.name
        self.out = os.path.join(self.dir, "masks")

    def tearDown(self):
        self.tmp.cleanup()

    def write_cvat(self, folder):
        os.makedirs(os.path.join(folder, "SegmentationClass"))
        with open(os.path.join(folder, "labelmap.txt"), "w") as out:
            out.write("# label:color_rgb:parts:actions\nbackground:0,0,0::\ncarrot:250,50,83::\nweed:36,179,83::\n")
        rgb = np.zeros((6, 8, 3), np.uint8)
        rgb[1:3, 1:3] = (250, 50, 83)
        rgb[4:6, 5:8] = (36, 179, 83)
        Image.fromarray(rgb).save(os.path.join(folder, "SegmentationClass", "field_01.png"))
        return rgb

    def test_cvat_segmentation_mask_export(self):
        export = os.path.join(self.dir, "cvat")
        self.write_cvat(export)
        written = import_source(export, self.out, mapping("carrot=crop,background=soil"))
        mask = read_mask(self.out, "field_01")
        expected = np.zeros((6, 8), np.uint8)
        expected[1:3, 1:3] = 1
        expected[4:6, 5:8] = 2
        np.testing.assert_array_equal(mask, expected)
        self.assertAlmostEqual(written["field_01"]["weed"], 6 / 48, places=3)

    def test_cvat_palette_pngs_are_decoded_by_colour(self):
        export = os.path.join(self.dir, "cvat")
        self.write_cvat(export)
        indices = np.zeros((6, 8), np.uint8)
        indices[4:6, 5:8] = 1  # palette entry 1 is the weed colour, not class 1
        image = Image.fromarray(indices, mode="P")
        image.putpalette([0, 0, 0, 36, 179, 83] + [0, 0, 0] * 254)
        image.save(os.path.join(export, "SegmentationClass", "field_01.png"))
        import_source(export, self.out, mapping("carrot=crop,background=soil"))
        self.assertEqual(int(read_mask(self.out, "field_01")[5, 6]), 2)

    def test_cvat_zip_export(self):
        export = os.path.join(self.dir, "cvat")
        self.write_cvat(export)
        archive = os.path.join(self.dir, "export.zip")
        with zipfile.ZipFile(archive, "w") as out:
            for root, _, files in os.walk(export):
                for name in files:
                    path = os.path.join(root, name)
                    out.write(path, os.path.relpath(path, export))
        import_source(archive, self.out, mapping("carrot=crop,background=soil"))
        self.assertEqual(int(read_mask(self.out, "field_01")[1, 1]), 1)

    def test_unknown_colour_names_the_file_and_colour(self):
        export = os.path.join(self.dir, "cvat")
        rgb = self.write_cvat(export)
        rgb[0, 0] = (1, 2, 3)
        Image.fromarray(rgb).save(os.path.join(export, "SegmentationClass", "field_01.png"))
        with self.assertRaises(LabelError) as caught:
            import_source(export, self.out, mapping("carrot=crop,background=soil"))
        self.assertIn("field_01.png", str(caught.exception))
        self.assertIn("1,2,3", str(caught.exception))

    def test_palette_png_reads_raw_indices(self):
        folder = os.path.join(self.dir, "palette")
        os.makedirs(folder)
        indices = np.array([[0, 1, 1], [2, 255, 0]], np.uint8)
        image = Image.fromarray(indices, mode="P")
        image.putpalette([0, 0, 0, 0, 255, 0, 255, 0, 0] + [200, 200, 200] * 253)
        image.save(os.path.join(folder, "plot7.png"))
        import_source(folder, self.out, mapping("0=soil,1=crop,2=weed,255=ignore"))
        np.testing.assert_array_equal(read_mask(self.out, "plot7"), [[0, 1, 1], [2, IGNORE, 0]])

    def test_crop_only_labels_call_green_soil_weed(self):
        import synthetic

        field = os.path.join(self.dir, "field")
        images, masks = synthetic.write_field(field, ["f1"])
        crop_only = os.path.join(self.dir, "crop-only")
        os.makedirs(crop_only)
        truth = read_mask(masks, "f1")
        cv2.imwrite(os.path.join(crop_only, "f1.png"), (truth == 1).astype(np.uint8))
        import_source(crop_only, self.out, mapping("0=soil,1=crop"), images=images, green_soil="weed")
        relabelled = read_mask(self.out, "f1")
        np.testing.assert_array_equal(relabelled == 1, truth == 1)
        weed = truth == 2
        self.assertGreater(np.mean(relabelled[weed] == 2), 0.95)  # the unlabelled weeds
        self.assertLess(np.mean(relabelled[truth == 0] == 2), 0.1)  # soil stays soil, but for a rim
        with self.assertRaises(LabelError):
            import_source(crop_only, self.out, mapping("0=soil,1=crop"), green_soil="weed")

    def test_labelme_polygons_later_over_earlier(self):
        document = {
            "imagePath": "../photos/row3.jpg", "imageHeight": 40, "imageWidth": 60,
            "shapes": [
                {"label": "carrot", "shape_type": "polygon", "points": [[10, 10], [50, 10], [50, 30], [10, 30]]},
                {"label": "thistle", "shape_type": "rectangle", "points": [[20, 15], [25, 20]]},
                {"label": "stake", "shape_type": "line", "points": [[0, 0], [5, 5]]},
            ],
        }
        with open(os.path.join(self.dir, "row3.json"), "w") as out:
            json.dump(document, out)
        with contextlib.redirect_stdout(io.StringIO()):
            import_source(os.path.join(self.dir, "row3.json"), self.out,
                          mapping("carrot=crop,thistle=weed,stake=ignore", unlabelled="ignore"))
        mask = read_mask(self.out, "row3")
        self.assertEqual(mask.shape, (40, 60))
        self.assertEqual(int(mask[12, 12]), 1)
        self.assertEqual(int(mask[17, 22]), 2)
        self.assertEqual(int(mask[2, 2]), IGNORE)

    def test_labelme_mask_shape(self):
        patch = np.zeros((4, 4), np.uint8)
        patch[1:3, 1:3] = 255
        encoded = base64.b64encode(cv2.imencode(".png", patch)[1].tobytes()).decode()
        document = {"imagePath": "m.jpg", "imageHeight": 10, "imageWidth": 10,
                    "shapes": [{"label": "weed", "shape_type": "mask", "points": [[2, 3], [5, 6]], "mask": encoded}]}
        with open(os.path.join(self.dir, "m.json"), "w") as out:
            json.dump(document, out)
        import_source(os.path.join(self.dir, "m.json"), self.out, mapping())
        mask = read_mask(self.out, "m")
        self.assertEqual(int(mask[4, 3]), 2)
        self.assertEqual(int(mask[3, 2]), 0)

    def test_coco_polygons_and_rle(self):
        weed = np.zeros((20, 30), bool)
        weed[2:5, 20:26] = True
        document = {
            "categories": [{"id": 1, "name": "lettuce"}, {"id": 2, "name": "weed"}],
            "images": [{"id": 7, "file_name": "shots/a.jpg", "height": 20, "width": 30},
                       {"id": 8, "file_name": "b.jpg", "height": 20, "width": 30}],
            "annotations": [
                {"id": 1, "image_id": 7, "category_id": 1, "iscrowd": 0,
                 "segmentation": [[2, 2, 12, 2, 12, 12, 2, 12]]},
                {"id": 2, "image_id": 7, "category_id": 2, "segmentation": [[5, 5, 8, 5, 8, 8, 5, 8]], "iscrowd": 0},
                {"id": 3, "image_id": 7, "category_id": 2, "iscrowd": 1,
                 "segmentation": {"counts": rle_counts(weed), "size": [20, 30]}},
                {"id": 4, "image_id": 8, "category_id": 2, "iscrowd": 1,
                 "segmentation": {"counts": rle_counts_to_string(rle_counts(weed)), "size": [20, 30]}},
            ],
        }
        path = os.path.join(self.dir, "instances.json")
        with open(path, "w") as out:
            json.dump(document, out)
        import_source(path, self.out, mapping("lettuce=crop"))
        a, b = read_mask(self.out, "a"), read_mask(self.out, "b")
        self.assertEqual(int(a[3, 3]), 1)
        self.assertEqual(int(a[6, 6]), 2)
        self.assertEqual(int(a[15, 15]), 0)
        np.testing.assert_array_equal(a[2:5, 20:26], 2)
        np.testing.assert_array_equal(b == 2, weed)

    def test_compressed_rle_round_trip(self):
        counts = [5, 3, 120, 1, 0, 7, 64]
        self.assertEqual(rle_counts_from_string(rle_counts_to_string(counts)), counts)

    def test_unmapped_label_names_file_and_label(self):
        document = {"imagePath": "x.jpg", "imageHeight": 5, "imageWidth": 5,
                    "shapes": [{"label": "parsnip", "points": [[0, 0], [4, 0], [4, 4]]}]}
        path = os.path.join(self.dir, "x.json")
        with open(path, "w") as out:
            json.dump(document, out)
        with self.assertRaises(LabelError) as caught:
            import_source(path, self.out, mapping())
        self.assertIn("x.json", str(caught.exception))
        self.assertIn("'parsnip'", str(caught.exception))

    def test_map_to_unknown_class_is_an_error(self):
        with self.assertRaises(LabelError) as caught:
            mapping("carrot=crops")
        self.assertIn("crops", str(caught.exception))

    def test_command_line_exits_with_the_message(self):
        document = {"imagePath": "x.jpg", "imageHeight": 5, "imageWidth": 5,
                    "shapes": [{"label": "parsnip", "points": [[0, 0], [4, 0], [4, 4]]}]}
        path = os.path.join(self.dir, "x.json")
        with open(path, "w") as out:
            json.dump(document, out)
        with self.assertRaises(SystemExit) as caught:
            import_labels.main([path, "--out", self.out])
        self.assertIn("parsnip", str(caught.exception))
        with contextlib.redirect_stdout(io.StringIO()) as printed:
            import_labels.main([path, "--out", self.out, "--map", "parsnip=crop", "--unlabelled", "ignore"])
        self.assertIn("1 masks", printed.getvalue())
        mask = read_mask(self.out, "x")
        self.assertEqual(int(mask[4, 0]), IGNORE)
        self.assertEqual(int(mask[1, 3]), 1)


if __name__ == "__main__":
    unittest.main()
