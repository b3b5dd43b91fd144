# SPDX-License-Identifier: Apache-2.0
"""Label import: annotation tools' exports to the class-id masks train.py reads.

A mask is an 8-bit single-channel PNG named like its photo (STEM.png for STEM.jpg), one class
id per pixel (the position of the class in --classes: 0 soil, 1 crop, 2 weed by default) and
255 where nothing is labelled (no figure and no loss counts those pixels).

Formats (import_source picks one from what the source holds):
- cvat: CVAT's "Segmentation mask 1.1" export, a folder (or its .zip) with labelmap.txt
  (lines `name:r,g,b::`) and SegmentationClass/STEM.png colour masks.
- palette: a folder of PNG masks. Palette (mode P) and grey PNGs are read as raw indices, whose
  label names are the numbers ("0", "1", ...); with a labelmap (--labelmap, or labelmap.txt in
  the folder) the colours are decoded through it instead, as for colour PNGs.
- labelme: LabelMe JSON files (a file or a folder of them): shapes with a label and polygon,
  rectangle, circle or mask geometry, imagePath, imageHeight, imageWidth.
- coco: a COCO instance JSON: categories, images, annotations whose segmentation is a polygon
  list or an RLE (uncompressed counts or the compressed string).
Polygons are painted in the order listed, so a later shape covers an earlier one; pixels outside
every shape are `unlabelled` (soil by default, or ignore). Lines and points carry no area and are
skipped with a warning.

Label names map to classes through a mapping like "carrot=crop,weed=weed,background=soil"; a
label named like a class (or "ignore") needs no entry. A label without a mapping is an error
naming the file and the label.
"""

import base64
import glob
import json
import os
import shutil
import tempfile
import zipfile

import cv2
import numpy as np

IGNORE = 255
IGNORE_NAME = "ignore"
FORMATS = ("auto", "cvat", "palette", "labelme", "coco")


class LabelError(Exception):
    """An export that cannot be converted; the message names the file and what is wrong."""


def parse_map(texts):
    """"a=b,c=d" (or a list of such strings) -> {"a": "b", "c": "d"}."""
    if isinstance(texts, str):
        texts = [texts]
    mapping = {}
    for text in texts or ():
        for item in filter(None, (part.strip() for part in text.split(","))):
            source, sep, target = item.partition("=")
            if not sep or not source.strip() or not target.strip():
                raise LabelError(f"--map '{item}': expected SOURCE_LABEL=CLASS, e.g. carrot=crop")
            mapping[source.strip()] = target.strip()
    return mapping


class LabelMapping:
    """Source label name -> class id (255 for ignore)."""

    def __init__(self, classes, mapping=None, unlabelled="soil"):
        self.classes = list(classes)
        targets = {name: i for i, name in enumerate(self.classes)}
        targets[IGNORE_NAME] = IGNORE
        self.targets = targets
        self.mapping = {}
        for source, target in (mapping or {}).items():
            if target not in targets:
                raise LabelError(f"--map {source}={target}: '{target}' is not one of {', '.join(targets)}")
            self.mapping[source] = targets[target]
        if unlabelled not in targets:
            raise LabelError(f"--unlabelled {unlabelled}: expected one of {', '.join(targets)}")
        self.unlabelled = targets[unlabelled]

    def class_id(self, label, source):
        label = str(label)
        for table in (self.mapping, self.targets):
            if label in table:
                return table[label]
        folded = {key.lower(): value for key, value in {**self.targets, **self.mapping}.items()}
        if label.lower() in folded:
            return folded[label.lower()]
        raise LabelError(f"{source}: label '{label}' has no mapping: add --map '{label}=CLASS' "
                         f"(CLASS one of {', '.join(self.targets)})")


def read_labelmap(path):
    """CVAT/VOC labelmap.txt -> [(name, (r, g, b))] in file order."""
    entries = []
    with open(path) as lines:
        for number, line in enumerate(lines, 1):
            line = line.strip()
            if not line or line.startswith("#"):
                continue
            parts = line.rsplit(":", 3) if line.count(":") >= 3 else line.split(":")
            try:
                rgb = tuple(int(v) for v in parts[1].split(","))
            except (IndexError, ValueError):
                rgb = ()
            if len(rgb) != 3 or not parts[0]:
                raise LabelError(f"{path}:{number}: expected 'name:r,g,b::', got '{line}'")
            entries.append((parts[0], rgb))
    if not entries:
        raise LabelError(f"{path}: no labels")
    return entries


def read_png(path, colour=False):
    """("index", 2-D array) for palette/grey PNGs, ("colour", H x W x 3 RGB) for colour ones
    or when colour is asked for (palettes turned into their colours)."""
    try:
        from PIL import Image
    except ImportError:
        return _read_png_cv2(path, colour)
    try:
        with Image.open(path) as image:
            if image.mode in ("P", "L", "I", "I;16") and not colour:
                return "index", np.array(image)
            return "colour", np.array(image.convert("RGB"))
    except OSError as error:
        raise LabelError(f"{path}: cannot read ({error})")


def _read_png_cv2(path, colour):
    """Without PIL: OpenCV gives palette PNGs as their colours, so only grey ones as indices."""
    raw = cv2.imread(path, cv2.IMREAD_UNCHANGED)
    if raw is None:
        raise LabelError(f"{path}: cannot read")
    if raw.ndim == 2:
        return ("colour", cv2.cvtColor(raw, cv2.COLOR_GRAY2RGB)) if colour else ("index", raw)
    return "colour", cv2.cvtColor(raw[..., :3], cv2.COLOR_BGR2RGB)


def decode_colour_mask(rgb, colours, mapping, source):
    """Colour mask + [(name, (r, g, b))] -> class ids; unknown colours are an error."""
    keys = (rgb[..., 0].astype(np.int64) << 16) | (rgb[..., 1].astype(np.int64) << 8) | rgb[..., 2]
    known = {(r << 16) | (g << 8) | b: name for name, (r, g, b) in colours}
    values, inverse = np.unique(keys, return_inverse=True)
    ids = np.zeros(len(values), np.uint8)
    for i, key in enumerate(values):
        if int(key) not in known:
            colour = f"{key >> 16},{(key >> 8) & 255},{key & 255}"
            raise LabelError(f"{source}: colour {colour} ({int((inverse == i).sum())} px) is not in the labelmap")
        ids[i] = mapping.class_id(known[int(key)], source)
    return ids[inverse].reshape(keys.shape)


def decode_index_mask(indices, mapping, source):
    """Index mask -> class ids; label names are the indices as text ("0", "1", ...)."""
    values, inverse = np.unique(indices, return_inverse=True)
    ids = np.array([mapping.class_id(str(int(v)), source) for v in values], np.uint8)
    return ids[inverse].reshape(indices.shape)


def _polygon(points):
    return np.round(np.asarray(points, np.float64).reshape(-1, 2)).astype(np.int32)


def paint_shape(canvas, shape, value):
    """Paints one shape (kind, geometry) with value; False when it has no area."""
    kind, geometry = shape
    if kind == "polygon":
        points = _polygon(geometry)
        if len(points) < 3:
            return False
        cv2.fillPoly(canvas, [points], int(value))
    elif kind == "rectangle":
        (x0, y0), (x1, y1) = _polygon(geometry)[:2]
        corners = (int(min(x0, x1)), int(min(y0, y1))), (int(max(x0, x1)), int(max(y0, y1)))
        cv2.rectangle(canvas, *corners, int(value), -1)
    elif kind == "circle":
        (cx, cy), (ex, ey) = np.asarray(geometry, np.float64)[:2]
        cv2.circle(canvas, (int(round(cx)), int(round(cy))), int(round(np.hypot(ex - cx, ey - cy))), int(value), -1)
    elif kind == "bitmap":
        canvas[np.asarray(geometry, bool)] = value
    else:
        return False
    return True


def rasterise(shapes, height, width, mapping, source):
    """[(label, (kind, geometry))] -> class ids; later shapes over earlier ones."""
    canvas = np.full((height, width), mapping.unlabelled, np.uint8)
    for label, shape in shapes:
        value = mapping.class_id(label, source)
        if not paint_shape(canvas, shape, value):
            print(f"{source}: shape '{label}' ({shape[0]}) has no area, skipped", flush=True)
    return canvas


def _stem(name):
    return os.path.splitext(os.path.basename(str(name).replace("\\", "/")))[0]


def labelme_shapes(document, source):
    """LabelMe JSON -> (stem, height, width, [(label, (kind, geometry))])."""
    try:
        height, width = int(document["imageHeight"]), int(document["imageWidth"])
    except (KeyError, TypeError, ValueError):
        raise LabelError(f"{source}: no imageHeight/imageWidth")
    shapes = []
    for number, shape in enumerate(document.get("shapes", [])):
        if "label" not in shape:
            raise LabelError(f"{source}: shape {number} has no label")
        kind = shape.get("shape_type") or "polygon"
        geometry = shape.get("points", [])
        if kind == "mask":
            kind, geometry = "bitmap", _labelme_bitmap(shape, height, width, source)
        shapes.append((shape["label"], (kind, geometry)))
    stem = _stem(document.get("imagePath") or os.path.basename(source))
    return stem, height, width, shapes


def _labelme_bitmap(shape, height, width, source):
    data = np.frombuffer(base64.b64decode(shape.get("mask", "")), np.uint8)
    patch = cv2.imdecode(data, cv2.IMREAD_GRAYSCALE) if data.size else None
    if patch is None:
        raise LabelError(f"{source}: mask shape '{shape['label']}' has no readable mask")
    full = np.zeros((height, width), bool)
    x, y = (int(round(v)) for v in shape["points"][0])
    region = full[y : y + patch.shape[0], x : x + patch.shape[1]]
    region[...] = patch[: region.shape[0], : region.shape[1]] > 0
    return full


def rle_counts_from_string(text):
    """COCO's compressed RLE string -> run lengths (pycocotools' rleFrString)."""
    counts, position = [], 0
    while position < len(text):
        value, shift, more = 0, 0, True
        while more:
            chunk = ord(text[position]) - 48
            value |= (chunk & 0x1F) << (5 * shift)
            more = bool(chunk & 0x20)
            position += 1
            shift += 1
            if not more and chunk & 0x10:
                value |= -1 << (5 * shift)
        if len(counts) > 2:
            value += counts[-2]
        counts.append(value)
    return counts


def rle_decode(rle, height, width, source):
    """COCO RLE (column-major runs starting with background) -> bool H x W."""
    counts = rle["counts"]
    if isinstance(counts, str):
        counts = rle_counts_from_string(counts)
    size = rle.get("size", [height, width])
    flat = np.zeros(int(size[0]) * int(size[1]), bool)
    position, value = 0, False
    for run in counts:
        flat[position : position + int(run)] = value
        position += int(run)
        value = not value
    if position != flat.size:
        raise LabelError(f"{source}: RLE covers {position} px, image has {flat.size}")
    return flat.reshape(int(size[1]), int(size[0])).T


def coco_images(document, source):
    """COCO instance JSON -> [(stem, height, width, [(label, (kind, geometry))])]."""
    try:
        names = {c["id"]: c["name"] for c in document["categories"]}
        images = {i["id"]: i for i in document["images"]}
    except (KeyError, TypeError):
        raise LabelError(f"{source}: not a COCO instance file (needs categories, images, annotations)")
    shapes = {image_id: [] for image_id in images}
    for number, annotation in enumerate(document.get("annotations", [])):
        image = images.get(annotation.get("image_id"))
        for key, table in (("image_id", images), ("category_id", names)):
            if annotation.get(key) not in table:
                raise LabelError(f"{source}: annotation {number}: {key} {annotation.get(key)} is not listed")
        label = names[annotation["category_id"]]
        segmentation = annotation.get("segmentation")
        if isinstance(segmentation, dict):
            bitmap = rle_decode(segmentation, image["height"], image["width"], source)
            shapes[image["id"]].append((label, ("bitmap", bitmap)))
        else:
            shapes[image["id"]] += [(label, ("polygon", part)) for part in segmentation or []]
    return [(_stem(image["file_name"]), int(image["height"]), int(image["width"]), shapes[image_id])
            for image_id, image in images.items()]


def _load_json(path):
    try:
        with open(path) as text:
            return json.load(text)
    except (OSError, ValueError) as error:
        raise LabelError(f"{path}: cannot read JSON ({error})")


def detect_format(source):
    """(format, path to read) of a source path (see the module docstring)."""
    if os.path.isdir(source):
        if all(os.path.exists(os.path.join(source, name)) for name in ("labelmap.txt", "SegmentationClass")):
            return "cvat", source
        coco = sorted(glob.glob(os.path.join(source, "annotations", "*.json")))
        if len(coco) == 1:
            return "coco", coco[0]
        if glob.glob(os.path.join(source, "*.json")):
            return "labelme", source
        if glob.glob(os.path.join(source, "*.png")):
            return "palette", source
        raise LabelError(f"{source}: no labelmap.txt + SegmentationClass/, annotations/*.json, *.json or *.png here")
    if source.lower().endswith(".json"):
        document = _load_json(source)
        if isinstance(document, dict) and "annotations" in document and "images" in document:
            return "coco", source
        if isinstance(document, dict) and "shapes" in document:
            return "labelme", source
        raise LabelError(f"{source}: JSON that is neither COCO (images, annotations) nor LabelMe (shapes)")
    if source.lower().endswith(".png"):
        return "palette", source
    raise LabelError(f"{source}: cannot tell the format (a folder, .zip, .json or .png)")


def masks_from_cvat(folder, mapping, labelmap=None):
    colours = read_labelmap(labelmap or os.path.join(folder, "labelmap.txt"))
    paths = sorted(glob.glob(os.path.join(folder, "SegmentationClass", "**", "*.png"), recursive=True))
    if not paths:
        raise LabelError(f"{folder}: SegmentationClass/ holds no PNG")
    for path in paths:
        yield _stem(path), decode_colour_mask(read_png(path, colour=True)[1], colours, mapping, path)


def masks_from_pngs(source, mapping, labelmap=None):
    paths = [source] if os.path.isfile(source) else sorted(glob.glob(os.path.join(source, "*.png")))
    if labelmap is None and os.path.isdir(source) and os.path.exists(os.path.join(source, "labelmap.txt")):
        labelmap = os.path.join(source, "labelmap.txt")
    colours = read_labelmap(labelmap) if labelmap else None
    for path in paths:
        kind, pixels = read_png(path, colour=colours is not None)
        if colours is not None:
            yield _stem(path), decode_colour_mask(pixels, colours, mapping, path)
        elif kind == "index":
            yield _stem(path), decode_index_mask(pixels, mapping, path)
        else:
            raise LabelError(f"{path}: a colour mask; give --labelmap FILE (lines 'name:r,g,b::') to name its colours")


def masks_from_labelme(source, mapping):
    paths = [source] if os.path.isfile(source) else sorted(glob.glob(os.path.join(source, "*.json")))
    for path in paths:
        stem, height, width, shapes = labelme_shapes(_load_json(path), path)
        yield stem, rasterise(shapes, height, width, mapping, path)


def masks_from_coco(path, mapping):
    for stem, height, width, shapes in coco_images(_load_json(path), path):
        if not shapes and mapping.unlabelled == IGNORE:
            print(f"{path}: {stem} has no annotation and --unlabelled ignore: no mask written", flush=True)
            continue
        yield stem, rasterise(shapes, height, width, mapping, f"{path} ({stem})")


def iter_masks(source, mapping, fmt="auto", labelmap=None):
    """(stem, class-id mask) pairs of a source in the given format (auto: detected)."""
    if fmt == "auto":
        fmt, source = detect_format(source)
    if fmt == "cvat":
        return masks_from_cvat(source, mapping, labelmap)
    if fmt == "palette":
        return masks_from_pngs(source, mapping, labelmap)
    if fmt == "labelme":
        return masks_from_labelme(source, mapping)
    if fmt == "coco":
        return masks_from_coco(source, mapping)
    raise LabelError(f"format '{fmt}': expected one of {', '.join(FORMATS)}")


def check_against_image(images, stem, mask):
    """The photo images/STEM.* (BGR); error unless it exists with the mask's size."""
    from evaluate import IMAGE_SUFFIXES

    for suffix in IMAGE_SUFFIXES:
        path = os.path.join(images, stem + suffix)
        if os.path.exists(path):
            image = cv2.imread(path, cv2.IMREAD_COLOR)
            if image is None or image.shape[:2] != mask.shape:
                found = "unreadable" if image is None else f"{image.shape[1]}x{image.shape[0]}"
                raise LabelError(f"{path}: {found}, but its mask is {mask.shape[1]}x{mask.shape[0]}")
            return image
    raise LabelError(f"--images {images}: no photo named {stem}.* for its mask")


def relabel_green_soil(mask, image, soil_id, green_id):
    """Sets labelled-soil pixels that a colour index calls green to green_id (a set that labels
    only the crop leaves its weeds as 'soil': they become weed, or ignore)."""
    from datasets import green_mask

    mask[(mask == soil_id) & green_mask(image)] = green_id


def import_source(source, out_dir, mapping, fmt="auto", labelmap=None, images=None, green_soil=None):
    """Writes out_dir/STEM.png for every mask of source; returns {stem: {class: pixel share}}.
    green_soil (a class name or "ignore", needs images): what green pixels labelled soil become."""
    if green_soil and not images:
        raise LabelError("--green-soil needs --images (the photos say which pixels are green)")
    green_id = None if not green_soil else mapping.class_id(green_soil, "--green-soil")
    with _unpacked(source) as folder:
        os.makedirs(out_dir, exist_ok=True)
        written = {}
        for stem, mask in iter_masks(folder, mapping, fmt, labelmap):
            if stem in written:
                raise LabelError(f"{source}: two masks for '{stem}'")
            if images:
                image = check_against_image(images, stem, mask)
                if green_id is not None:
                    relabel_green_soil(mask, image, mapping.class_id("soil", "--classes"), green_id)
            cv2.imwrite(os.path.join(out_dir, stem + ".png"), mask)
            written[stem] = class_shares(mask, mapping.classes)
    if not written:
        raise LabelError(f"{source}: no masks found")
    return written


def class_shares(mask, classes):
    counts = np.bincount(mask.ravel(), minlength=256)
    names = list(classes) + [IGNORE_NAME]
    ids = list(range(len(classes))) + [IGNORE]
    return {name: round(float(counts[i]) / mask.size, 4) for name, i in zip(names, ids)}


class _unpacked:
    """A .zip source extracted to a temporary folder for the duration; other sources as they are."""

    def __init__(self, source):
        self.source = source
        self.temp = None

    def __enter__(self):
        if not (os.path.isfile(self.source) and zipfile.is_zipfile(self.source)):
            return self.source
        self.temp = tempfile.mkdtemp(prefix="labels-")
        with zipfile.ZipFile(self.source) as archive:
            archive.extractall(self.temp)
        entries = os.listdir(self.temp)
        inner = os.path.join(self.temp, entries[0]) if len(entries) == 1 else self.temp
        return inner if os.path.isdir(inner) else self.temp

    def __exit__(self, *exc):
        if self.temp:
            shutil.rmtree(self.temp, ignore_errors=True)
