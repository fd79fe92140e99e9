"""Train the door model (``models/door_columns.onnx``) and export it to ONNX.

:func:`augment.room.openings.find_openings` samples every wall of the measured floor as a
front-on strip; this model says, per column of the strip, whether a door stands there. It
reads what :func:`augment.room.openings.column_features` gives (the column's colours
from the floor to 2.4 m, less the wall's own, its lightness, the steps across it) and
looks along the wall with dilated convolutions, so it sees a casing's two sides and a
door's head together. It learns from renders of the synthetic photographer, measured by
the shipped pipeline, whose true doors are mapped to the walls found.

Recipe (what ``models/door_columns.onnx`` was made with: 840 renders, 1,952 walls, 376
with a door; about 45 minutes of rendering on two cores, 4 of training)::

    python models/train_doors.py render --seeds $(seq 9450 9463) --count 60 \\
        --cache data/doors                      # in Stager's environment
    python models/train_doors.py train --cache data/doors --val 9457 --epochs 30 \\
        --out models/door_columns.onnx          # where torch is installed

Rendered walls are kept in ``--cache`` (one file per seed). Everything random derives
from ``--seed``. Training needs torch (``pip install -e '.[train]'``); Stager runs the
exported model with onnxruntime.
"""
from __future__ import annotations

import argparse
import copy
import json
import multiprocessing
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

# Columns this close to a door's side are neither door nor wall (the casing, blur).
UNSURE_M = 0.04
# A true door belongs to a wall found when its middle lies this close to the wall's line.
ON_WALL_M = 0.3
# Training windows, columns (5.12 m of wall), and the wall's ends padded with this many
# columns of nothing in view, as :func:`augment.room.openings.door_probability` pads them.
WINDOW = 256
MARGIN = 64
# Door columns weigh this much more than wall columns: doors are rarer, and a missed one
# costs more (furniture across it) than a false one (a zone kept clear).
POS_WEIGHT = 2.0


def render_walls(seed: int, count: int) -> dict:
    """Render ``count`` rooms of ``seed``, measure each as Stager does and return every
    wall's column features with per-column labels (1 door, 0 none, -1 unsure)."""
    from augment.camera.board import Board
    from augment.errors import StagerError
    from augment.pipeline import measure
    from augment.render.gl import Renderer
    from augment.room.openings import _lab, _walls, column_features
    from augment.room.settings import ROOM
    from augment.synth import render_sample
    from augment.synth.photo import save_as_phone
    from augment.synth.truth import true_doors_on_floor

    walls, labels, render = [], [], []
    work = Path(tempfile.mkdtemp())
    with Renderer() as renderer:
        for i in range(count):
            sample = render_sample([seed, i], renderer, clutter=False)
            path = work / f"{i}.jpg"
            save_as_phone(path, sample.image, sample.truth["K"][0][0], sample.truth["photo"]["jpeg_quality"])
            try:
                m = measure(path, Board())
            except StagerError:
                continue
            doors = true_doors_on_floor(sample.truth, m.calibration.camera_from_floor)
            lab = _lab(m.image)
            poly = np.asarray(m.floor.polygon_m, dtype=np.float64)
            for a, b in _walls(poly, m.floor.edge_kind, ROOM.doors):
                length = float(np.linalg.norm(b - a))
                if length < ROOM.doors.width_m[0]:
                    continue
                got = column_features(lab, m.calibration, a, b)
                if got is None:
                    continue
                features, s = got
                u = (b - a) / length
                n = np.array([-u[1], u[0]])
                label = np.zeros(len(s), np.int8)
                for d in doors:
                    if abs((d.mean(axis=0) - a) @ n) > ON_WALL_M:
                        continue
                    t0, t1 = np.sort((d - a) @ u)
                    label[(s > t0 - UNSURE_M) & (s < t1 + UNSURE_M)] = -1
                    label[(s >= t0 + UNSURE_M) & (s <= t1 - UNSURE_M)] = 1
                walls.append(features)
                labels.append(label)
                render.append(i)
    return {"walls": walls, "labels": labels, "render": render}


def _render_job(job):
    seed, count, cache = job
    path = Path(cache) / f"walls_{seed}.npz"
    if path.exists():
        return f"{seed}: cached"
    t = time.perf_counter()
    got = render_walls(seed, count)
    lengths = np.array([w.shape[1] for w in got["walls"]], np.int64)
    np.savez_compressed(path, features=np.concatenate(got["walls"], axis=1) if got["walls"] else np.zeros((0, 0)),
                        labels=np.concatenate(got["labels"]) if got["labels"] else np.zeros(0, np.int8),
                        lengths=lengths, render=np.array(got["render"], np.int32))
    doors = int(sum((lab == 1).any() for lab in got["labels"]))
    return f"{seed}: {len(lengths)} walls, {doors} with a door, {time.perf_counter() - t:.0f} s"


def _load(cache: Path, seeds) -> list[tuple[np.ndarray, np.ndarray]]:
    out = []
    for seed in seeds:
        with np.load(cache / f"walls_{seed}.npz") as data:  # each key read once: a read decompresses
            features, labels, lengths = data["features"], data["labels"], data["lengths"]
        for end, length in zip(np.cumsum(lengths), lengths):
            out.append((features[:, end - length:end].copy(), labels[end - length:end].copy()))
    return out


def train(cache: Path, val: list[int], out: Path, epochs: int, seed: int) -> dict:
    import torch
    from torch import nn

    torch.manual_seed(seed)
    torch.set_num_threads(2)
    rng = np.random.default_rng(seed)
    seeds = sorted(int(p.stem.split("_")[1]) for p in cache.glob("walls_*.npz"))
    train_walls = _load(cache, [s for s in seeds if s not in val])
    val_walls = _load(cache, val)
    channels = train_walls[0][0].shape[0]
    rows = channels // 6  # six planes of samples up the wall (column_features)

    width = 48
    layers: list[nn.Module] = [nn.Conv1d(channels, width, 1), nn.ReLU()]
    for dilation in (1, 2, 4, 8, 16):
        layers += [nn.Conv1d(width, width, 5, padding=2 * dilation, dilation=dilation), nn.ReLU(), nn.Dropout(0.2)]
    layers += [nn.Conv1d(width, 1, 1)]
    model = nn.Sequential(*layers)
    loss_fn = nn.BCEWithLogitsLoss(reduction="none", pos_weight=torch.tensor(POS_WEIGHT))
    opt = torch.optim.AdamW(model.parameters(), lr=2e-3, weight_decay=1e-4)
    sched = torch.optim.lr_scheduler.CosineAnnealingLR(opt, epochs)

    def batch(walls):
        # Fixed-size windows: a random stretch of a longer wall, zeros past a shorter one
        # (onnxruntime takes any length; torch's CPU kernels grow their caches with each).
        x = np.zeros((len(walls), channels, WINDOW + 2 * MARGIN), np.float32)
        y = np.full((len(walls), WINDOW + 2 * MARGIN), -1, np.int8)
        for k, (w, lab) in enumerate(walls):
            w, lab = np.pad(w, ((0, 0), (MARGIN, MARGIN))), np.pad(lab, (MARGIN, MARGIN), constant_values=-1)
            start = int(rng.integers(0, w.shape[1] - WINDOW - 2 * MARGIN + 1)) if w.shape[1] > WINDOW + 2 * MARGIN \
                else 0
            n = min(w.shape[1], WINDOW + 2 * MARGIN)
            x[k, :, :n] = w[:, start:start + n]
            # The same door under other light: colour differences and lightness scaled.
            x[k, :3 * rows] *= rng.uniform(0.7, 1.3)
            x[k, 3 * rows:4 * rows] *= rng.uniform(0.8, 1.2)
            y[k, :n] = lab[start:start + n]
        return torch.from_numpy(x), torch.from_numpy(y.astype(np.float32))

    def evaluate(walls):
        model.eval()
        tp = fp = fn = 0
        loss = count = 0.0
        with torch.no_grad():
            for w, lab in walls:
                padded = np.zeros((1, channels, -(-(w.shape[1] + 2 * MARGIN) // WINDOW) * WINDOW), np.float32)
                padded[0, :, MARGIN:MARGIN + w.shape[1]] = w
                logits = model(torch.from_numpy(padded))[0, 0, MARGIN:MARGIN + w.shape[1]]
                known = torch.from_numpy(lab >= 0)
                y = torch.from_numpy((lab == 1).astype(np.float32))
                loss += float(loss_fn(logits, y)[known].sum())
                count += int(known.sum())
                p = logits.numpy() > 0
                tp += int((p & (lab == 1)).sum())
                fp += int((p & (lab == 0)).sum())
                fn += int((~p & (lab == 1)).sum())
        return {"loss": round(loss / max(count, 1), 4), "precision": round(tp / max(tp + fp, 1), 3),
                "recall": round(tp / max(tp + fn, 1), 3)}

    best, log = None, []
    for epoch in range(epochs):
        model.train()
        order = rng.permutation(len(train_walls))
        total = 0.0
        for k in range(0, len(order), 16):
            chunk = [train_walls[j] for j in order[k:k + 16]]
            # Flipped walls too: a door reads the same from either end.
            chunk = [(w[:, ::-1].copy(), lab[::-1].copy()) if rng.random() < 0.5 else (w, lab) for w, lab in chunk]
            x, y = batch(chunk)
            logits = model(x)[:, 0]
            weight = (y >= 0).float()
            loss = (loss_fn(logits, y.clamp(min=0)) * weight).sum() / weight.sum().clamp(min=1)
            opt.zero_grad()
            loss.backward()
            opt.step()
            total += float(loss.detach()) * len(chunk)
        sched.step()
        scores = evaluate(val_walls)
        log.append({"epoch": epoch + 1, "train_loss": round(total / len(train_walls), 4), "val": scores})
        print(f"epoch {epoch + 1}: loss {total / len(train_walls):.4f} val {scores}", flush=True)
        if best is None or scores["loss"] < best[0]["loss"]:
            best = (scores, epoch + 1, copy.deepcopy(model.state_dict()))

    model.load_state_dict(best[2])
    model.eval()
    out.parent.mkdir(parents=True, exist_ok=True)
    torch.onnx.export(model, torch.zeros(1, channels, 64), str(out), input_names=["features"],
                      output_names=["door"], dynamic_axes={"features": {2: "columns"}, "door": {2: "columns"}},
                      opset_version=17, dynamo=False)
    result = {"train_walls": len(train_walls), "val_walls": len(val_walls), "val": best[0], "best_epoch": best[1],
              "channels": channels, "epochs": epochs, "seed": seed,
              "parameters": sum(p.numel() for p in model.parameters()), "seeds": seeds, "val_seeds": val,
              "pos_weight": POS_WEIGHT, "window": WINDOW, "margin": MARGIN, "log": log}
    out.with_suffix(".json").write_text(json.dumps(result, indent=1) + "\n")
    return result


def main(argv=None) -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = p.add_subparsers(dest="step", required=True)
    r = sub.add_parser("render", help="render and measure rooms; keep their walls in --cache")
    r.add_argument("--seeds", type=int, nargs="+", required=True)
    r.add_argument("--count", type=int, default=60)
    r.add_argument("--cache", type=Path, required=True)
    r.add_argument("--workers", type=int, default=2)
    t = sub.add_parser("train", help="train on the cached walls and export the model")
    t.add_argument("--cache", type=Path, required=True)
    t.add_argument("--val", type=int, nargs="+", required=True)
    t.add_argument("--out", type=Path, default=ROOT / "models" / "door_columns.onnx")
    t.add_argument("--epochs", type=int, default=40)
    t.add_argument("--seed", type=int, default=0)
    args = p.parse_args(argv)
    if args.step == "render":
        args.cache.mkdir(parents=True, exist_ok=True)
        jobs = [(s, args.count, str(args.cache)) for s in args.seeds]
        with multiprocessing.get_context("spawn").Pool(args.workers) as pool:
            for line in pool.imap_unordered(_render_job, jobs):
                print(line, flush=True)
    else:
        print(json.dumps(train(args.cache, args.val, args.out, args.epochs, args.seed), indent=1))


if __name__ == "__main__":
    main()
