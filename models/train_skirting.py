"""Train the skirting-board model (``models/skirting_board.onnx``) and export it to ONNX.

The skirting trim (``augment/skirting.py``) cuts a strip off the top of the floor mask
where a board seems to stand. Often the mask already ends at the floor line and the strip
it would cut is floor: this model says, per image column, whether the mask's edge is a
board's top edge. It reads what :func:`augment.floor.skirting.board_profiles` gives (the
column's colours from 10 cm above the mask's edge to 30 cm below it, in meters through
the calibration), and learns from renders of the synthetic photographer whose floor line
is known: segmented by the shipped pipeline without the trim, so the model sees the
masks the trim sees.

Recipe (what ``models/skirting_board.onnx`` was made with; 1,040 renders of the
photographer's 5-12 cm boards, 520 with boards of 10-20 cm, 520 with the trim painted
the floor's colour and 520 with it painted dark; 32 minutes of rendering on two cores for
the first 16 seeds and 8 for the dark ones, 28 of training beside another training)::

    python models/train_skirting.py --seeds 950 951 952 954 955 956 957 --tall-seeds 958 959 962 963 \\
        --hue-seeds 964 965 966 967 --dark-seeds 974 975 976 977 --val 953 --count 130 \\
        --out models/skirting_board.onnx

``--task gap`` trains the floor-line model (``models/skirting_gap.onnx``) from the same
rendered columns: per column, whether the floor line lies above the mask's edge (GrabCut
stopped short, below the shade at the foot of a wall) and by how many centimeters::

    python models/train_skirting.py --task gap --seeds 950 951 952 954 955 956 957 \\
        --tall-seeds 958 959 962 963 --hue-seeds 964 965 966 967 --val 953 --count 130 \\
        --epochs 8 --out models/skirting_gap.onnx

``--task depth`` trains the board-height model (``models/skirting_depth.onnx``) from the
same columns, those whose floor line lies 2.5-22 cm below the mask's edge: per column,
how far below (cm), so that the trim cuts at the board's lower edge rather than at the
strongest step, which on a grained floor or below a board's shadow is often another
(55 seconds of training)::

    python models/train_skirting.py --task depth --seeds 950 951 952 954 955 956 957 \\
        --tall-seeds 958 959 962 963 --hue-seeds 964 965 966 967 --dark-seeds 974 975 976 977 \\
        --val 953 --count 130 --cache data/skirting_v2 --out models/skirting_depth.onnx

Rendered columns are kept in ``--cache`` (one file per seed), so a second run trains
without rendering. Everything random derives from ``--seed``. Training needs torch
(``pip install -e '.[train]'``); Stager runs the exported model with onnxruntime.
"""
from __future__ import annotations

import argparse
import json
import multiprocessing
import sys
import time
import warnings
from pathlib import Path

import cv2
import numpy as np
import torch
from torch import nn

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from augment.floor.skirting import board_profiles, working_view  # noqa: E402

# A column's mask edge is a board's top when the floor line lies this far below it or
# more; columns between this and the first value are anti-aliasing, left out, and so
# are columns whose edge is far from any floor line (a carton's top, say).
BOARD_M, UNSURE_M = 0.025, 0.01
KEEP_FROM_M, KEEP_TO_M = -0.05, 0.22
# The photographer draws boards 5-12 cm tall; real ones reach 20 cm, and a check that
# never saw one takes it for no board. ``--tall-seeds`` are rendered with these.
TALL_BASEBOARD_M = (0.10, 0.20)
# The gap model: the floor line lies above the mask's edge when this far or farther;
# columns between this and the second value are anti-aliasing, left out, and so are
# columns whose floor line is more than the profile's reach above the edge.
GAP_M, GAP_UNSURE_M = -0.015, -0.005
GAP_FAR_M = -0.10
# Boards painted the floor's colour look like a band of light or shade on the floor, which
# the rules leave alone; ``--hue-seeds`` are rendered with every room's trim so painted.
# The photographer's trims are white or light wood; ``--dark-seeds`` paint them dark.
FLAVOURS = {"": {}, "tall": {"baseboard_m": TALL_BASEBOARD_M}, "hue": {"trim_like_floor": 1.0},
            "dark": {"trim_dark": 1.0}}


def render_columns(seed: int, count: int, flavour: str = "") -> dict:
    """Render ``count`` rooms of ``seed`` (with the render options of ``FLAVOURS[flavour]``),
    segment each without the trim and return every wall column's profile, scalars and
    true floor-line offset (m, NaN: no floor)."""
    from augment.camera.board import Board
    from augment.camera.calibrate import calibrate_photo, exif_intrinsics
    from augment.errors import CalibrationError
    from augment.render.gl import Renderer
    from augment.floor.model import DEFAULT_MODEL, FloorModel
    from augment.floor.segment import segment_floor
    from augment.synth import render_sample

    model = FloorModel(DEFAULT_MODEL)
    out = {"profile": [], "scalars": [], "offset_m": [], "render": []}
    with Renderer() as renderer:
        for i in range(count):
            sample = render_sample([seed, i], renderer, **FLAVOURS[flavour])
            w, h = sample.truth["size_px"]
            try:
                cal = calibrate_photo(sample.image, Board(),
                                      intrinsics=exif_intrinsics(sample.truth["K"][0][0], (w, h)))
            except CalibrationError:
                continue
            mask = segment_floor(sample.image, model, cal, skirting=False).mask
            view = working_view(sample.image, mask, cal) if mask.any() else None
            if view is None:
                continue
            _, small_image, small_mask, _, cols, rows, px_per_m = view
            profile, scalars, _ = board_profiles(small_image, small_mask, cols, rows, px_per_m)
            truth = cv2.resize(sample.floor_mask.astype(np.uint8), small_mask.shape[::-1],
                               interpolation=cv2.INTER_NEAREST) > 0
            floor_line = np.argmax(truth, axis=0)[cols]
            offset_m = np.where(truth[:, cols].any(axis=0), (floor_line - rows) / px_per_m, np.nan)
            out["profile"].append(profile)
            out["scalars"].append(scalars)
            out["offset_m"].append(offset_m.astype(np.float32))
            out["render"].append(np.full(len(cols), i, np.int32))
    return {k: np.concatenate(v) if v else np.zeros(0) for k, v in out.items()}


def _cache_path(cache: Path, seed: int, count: int, flavour: str) -> Path:
    return cache / f"skirting_{seed}_{count}{'_' + flavour if flavour else ''}.npz"


def load_seed(seed: int, count: int, cache: Path, flavour: str = "") -> dict:
    path = _cache_path(cache, seed, count, flavour)
    if not path.exists():
        data = render_columns(seed, count, flavour)
        cache.mkdir(parents=True, exist_ok=True)
        tmp = path.with_suffix(".tmp.npz")
        np.savez_compressed(tmp, **data)
        tmp.replace(path)
    with np.load(path) as f:
        return dict(f)


def labelled(data: dict, every: int, task: str = "board"):
    """Tensors of every ``every``-th usable column (neighbours are nearly the same). The
    target is, for the board model, 1 where the mask's edge is a board's top; for the gap
    model, (1 where the floor line lies above the edge, its offset in cm: 0 or less)."""
    off = data["offset_m"]
    if task == "board":
        near, unsure = KEEP_FROM_M, (UNSURE_M, BOARD_M)
    elif task == "depth":
        near, unsure = BOARD_M, (BOARD_M, BOARD_M)
    else:
        near, unsure = GAP_FAR_M, (GAP_M, GAP_UNSURE_M)
    usable = (np.isfinite(off) & (off > near) & (off < KEEP_TO_M)
              & ~((off > unsure[0]) & (off < unsure[1])))
    pick = np.flatnonzero(usable)[::every]
    o = off[pick]
    y = {"board": lambda: o > BOARD_M, "depth": lambda: 100 * o,
         "gap": lambda: np.column_stack([o < GAP_M, 100 * np.minimum(o, 0)])}[task]()
    return (torch.tensor(data["profile"][pick]), torch.tensor(data["scalars"][pick]),
            torch.tensor(y.astype(np.float32)))


class BoardNet(nn.Module):
    """Two 1-D convolutions along the column's profile, a pooling, and a small head that
    also sees the scalars. Output: one logit per column (board or not), or with
    ``outputs=2`` a row per column (the gap model's logit and offset in cm)."""

    def __init__(self, channels: int = 16, samples: int = 81, outputs: int = 1):
        super().__init__()
        self.conv = nn.Sequential(nn.Conv1d(7, channels, 5, padding=2), nn.ReLU(),
                                  nn.Conv1d(channels, channels, 5, padding=4, dilation=2), nn.ReLU(),
                                  nn.MaxPool1d(3, 3))
        self.head = nn.Sequential(nn.Dropout(0.2), nn.Linear(channels * (samples // 3) + 2, 32), nn.ReLU(),
                                  nn.Linear(32, outputs))
        self.outputs = outputs

    def forward(self, profile, scalars):
        out = self.head(torch.cat([self.conv(profile).flatten(1), scalars], 1))
        return out[:, 0] if self.outputs == 1 else out


def _gap_loss(out, y):
    """Cross-entropy of 'floor line above the edge', plus the offset's error (cm, Huber,
    weighted 0.2) where it is."""
    loss = nn.functional.binary_cross_entropy_with_logits(out[:, 0], y[:, 0])
    above = y[:, 0] > 0.5
    if above.any():
        loss = loss + 0.2 * nn.functional.smooth_l1_loss(out[above, 1], y[above, 1])
    return loss


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--task", choices=("board", "depth", "gap"), default="board",
                        help="board: is the mask's edge a board's top; depth: how far below it the floor "
                             "line lies where it is; gap: does the floor line lie above it")
    parser.add_argument("--seeds", type=int, nargs="+", required=True, help="render seeds to train on")
    parser.add_argument("--tall-seeds", type=int, nargs="*", default=[],
                        help="render seeds to train on, with baseboards of 10-20 cm")
    parser.add_argument("--hue-seeds", type=int, nargs="*", default=[],
                        help="render seeds to train on, with the trim painted the floor's colour")
    parser.add_argument("--dark-seeds", type=int, nargs="*", default=[],
                        help="render seeds to train on, with the trim painted a dark colour")
    parser.add_argument("--val", type=int, nargs="+", required=True, help="render seeds to validate on")
    parser.add_argument("--count", type=int, default=130, help="renders per seed")
    parser.add_argument("--epochs", type=int, default=10)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--workers", type=int, default=2, help="processes rendering seeds at once")
    parser.add_argument("--cache", type=Path, default=Path("data/skirting"))
    parser.add_argument("--out", type=Path, default=Path("models/skirting_board.onnx"))
    args = parser.parse_args(argv)

    t0 = time.time()
    train = ([(s, "") for s in args.seeds] + [(s, "tall") for s in args.tall_seeds]
             + [(s, "hue") for s in args.hue_seeds] + [(s, "dark") for s in args.dark_seeds])
    seeds = train + [(s, "") for s in args.val]
    missing = [(s, f) for s, f in seeds if not _cache_path(args.cache, s, args.count, f).exists()]
    if missing:
        with multiprocessing.get_context("spawn").Pool(min(args.workers, len(missing))) as pool:
            pool.starmap(load_seed, [(s, args.count, args.cache, f) for s, f in missing])
    data = {key: load_seed(key[0], args.count, args.cache, key[1]) for key in seeds}
    t_render = time.time() - t0

    def joined(group, every):
        parts = [labelled(data[key], every, args.task) for key in group]
        return [torch.cat(x) for x in zip(*parts)]

    profile, scalars, y = joined(train, 2)
    profile_v, scalars_v, y_v = joined([(s, "") for s in args.val], 4)
    gap, depth = args.task == "gap", args.task == "depth"
    if depth:
        print(f"{len(y)} training columns with a board (median {float(y.median()):.1f} cm), "
              f"{len(y_v)} validation", flush=True)
    else:
        share = float((y[:, 0] if gap else y).mean())
        print(f"{len(y)} training columns ({share:.1%} {'floor line above' if gap else 'board'}), "
              f"{len(y_v)} validation", flush=True)

    torch.manual_seed(args.seed)
    net = BoardNet(samples=profile.shape[2], outputs=2 if gap else 1)
    opt = torch.optim.AdamW(net.parameters(), 1e-3, weight_decay=1e-2)
    loss_fn = (_gap_loss if gap else nn.functional.smooth_l1_loss if depth
               else nn.functional.binary_cross_entropy_with_logits)
    log, best = [], (float("inf"), None)
    for epoch in range(args.epochs):
        net.train()
        order = torch.randperm(len(y))
        for start in range(0, len(y), 256):
            batch = order[start:start + 256]
            loss = loss_fn(net(profile[batch], scalars[batch]), y[batch])
            opt.zero_grad()
            loss.backward()
            opt.step()
        net.eval()
        with torch.no_grad():
            logits = net(profile_v, scalars_v)
            val_loss = float(loss_fn(logits, y_v))
            if depth:
                # the share of columns whose floor line it places within 1 cm
                val_acc = float(((logits - y_v).abs() <= 1.0).float().mean())
            else:
                said, told = (logits[:, 0], y_v[:, 0]) if gap else (logits, y_v)
                val_acc = float(((said > 0) == (told > 0.5)).float().mean())
        log.append({"epoch": epoch + 1, "val_loss": round(val_loss, 4), "val_accuracy": round(val_acc, 4)})
        if depth:
            log[-1]["val_depth_mae_cm"] = round(float((logits - y_v).abs().mean()), 3)
        if gap:
            above = y_v[:, 0] > 0.5
            log[-1]["val_offset_mae_cm"] = round(float((logits[above, 1] - y_v[above, 1]).abs().mean()), 3)
        print(log[-1], flush=True)
        if val_loss < best[0]:
            best = (val_loss, {k: v.clone() for k, v in net.state_dict().items()})
    net.load_state_dict(best[1])
    net.eval()

    output = "out" if gap else "depth_cm" if depth else "logit"
    args.out.parent.mkdir(parents=True, exist_ok=True)
    tmp = args.out.with_suffix(".tmp.onnx")
    with warnings.catch_warnings():  # the TorchScript exporter is deprecated, and does this model fine
        warnings.simplefilter("ignore", DeprecationWarning)
        torch.onnx.export(net, (profile_v[:4], scalars_v[:4]), str(tmp), input_names=["profile", "scalars"],
                          output_names=[output], opset_version=17, dynamo=False,
                          dynamic_axes={"profile": {0: "columns"}, "scalars": {0: "columns"},
                                        output: {0: "columns"}})
    tmp.replace(args.out)
    sidecar = {"task": args.task, "seeds": args.seeds, "tall_seeds": args.tall_seeds, "tall_baseboard_m": list(TALL_BASEBOARD_M),
               "hue_seeds": args.hue_seeds, "dark_seeds": args.dark_seeds,
               "val": args.val, "count": args.count, "seed": args.seed,
               "epochs": args.epochs, "kept_epoch": min(log, key=lambda e: e["val_loss"])["epoch"],
               "parameters": sum(p.numel() for p in net.parameters()), "training_columns": len(y),
               "render_s": round(t_render), "train_s": round(time.time() - t0 - t_render), "log": log}
    args.out.with_suffix(".json").write_text(json.dumps(sidecar, indent=1) + "\n")
    print(f"wrote {args.out} ({sidecar['train_s']} s training)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
