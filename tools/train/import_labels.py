#!/usr/bin/python3
# SPDX-License-Identifier: Apache-2.0
"""Converts labels from an annotation tool into the class-id masks train.py reads.

Reads a CVAT "Segmentation mask 1.1" export (folder or .zip), a folder of palette/grey PNG masks,
LabelMe JSON (a file or a folder) or a COCO instance JSON, and writes OUT/STEM.png: one byte per
pixel, the class id (0 soil, 1 crop, 2 weed with the default --classes), 255 = unlabelled.
See labels.py for what each format may hold.

    /usr/bin/python3 tools/train/import_labels.py ~/carrots/cvat-export.zip --out ~/carrots/masks \
        --map carrot=crop,weed=weed,background=soil --images ~/carrots/images

    /usr/bin/python3 tools/train/import_labels.py ~/carrots/labelme --out ~/carrots/masks \
        --map carrot=crop,weed=weed,_background_=soil --unlabelled ignore

Labels named like a class (soil, crop, weed) or "ignore" map to themselves; every other label
needs a --map entry, or the run stops naming the file and the label. --unlabelled sets what the
pixels outside every polygon are (LabelMe, COCO): soil (the default: label every plant) or
ignore (label only some plants; the rest counts for nothing). A set that labels only the crop
(as ../shared/data/cauliflower) can name its green unlabelled pixels: --green-soil weed (or
ignore). Prints each mask's class shares.

    /usr/bin/python3 tools/train/import_labels.py ../shared/data/cauliflower/masks --out /tmp/cw \
        --map 0=soil,1=crop --images ../shared/data/cauliflower/images --green-soil weed
"""

import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from labels import FORMATS, LabelError, LabelMapping, import_source, parse_map  # noqa: E402


def parse_args(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("source", help="export folder, .zip, .json or .png")
    parser.add_argument("--out", required=True, help="folder for the STEM.png class-id masks")
    parser.add_argument("--format", choices=FORMATS, default="auto")
    parser.add_argument("--map", action="append", default=[], metavar="LABEL=CLASS,...",
                        help="source label -> class (or ignore), e.g. carrot=crop,weed=weed,background=soil")
    parser.add_argument("--unlabelled", default="soil", help="class of pixels outside every polygon: soil or ignore")
    parser.add_argument("--classes", default="soil,crop,weed", help="class names in class-id order (as train.py)")
    parser.add_argument("--labelmap", help="labelmap.txt naming mask colours (name:r,g,b::), if not in the export")
    parser.add_argument("--images", help="photo folder: check each mask has a photo of the same size")
    parser.add_argument("--green-soil", metavar="CLASS",
                        help="for sets that label only the crop: pixels labelled soil that a colour index "
                             "calls green become CLASS (weed, or ignore); needs --images")
    return parser.parse_args(argv)


def main(argv=None):
    args = parse_args(argv)
    try:
        mapping = LabelMapping(args.classes.split(","), parse_map(args.map), args.unlabelled)
        written = import_source(args.source, args.out, mapping, args.format, args.labelmap, args.images,
                                args.green_soil)
    except LabelError as error:
        raise SystemExit(f"import_labels: {error}")
    for stem, shares in sorted(written.items()):
        print(f"{stem}: " + ", ".join(f"{name} {share:.1%}" for name, share in shares.items()))
    print(f"{len(written)} masks -> {args.out}")


if __name__ == "__main__":
    main()
