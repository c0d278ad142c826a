#!/usr/bin/python3
"""Bring your own model: train a small GRU edge model on a uavsim data set
and export it as TorchScript for `uavsim run`.

    build/uavsim dataset scenarios/default.json --episodes 40 --model models/default --out data.h5
    python3 examples/python/train_gru.py data.h5 --out mine.pt --seconds 60
    build/uavsim run scenarios/default.json \
        --set '/pipeline/methods=["uavloc","ekf",{"type":"torchscript","name":"mine","edge":"mine.pt"}]'

The model gets, at each window, exactly what uavsim's edge gives a
TorchScript method (pipeline/edge/scripted_edge.h; docs/dataset.md): for the
last L windows, per modality, the latents that arrived on time with their
capture offsets into the window and a mask. This script builds those tensors
from the HDF5 file by the same rule, so what it trains on is what the model
sees in the loop.

Uses only Debian's python3-torch (1.13.1, as uavsim's LibTorch), python3-h5py
and python3-numpy. Prints one JSON line (counts, shapes, the held-out RMSE)
on stdout.
"""
import argparse
import json
import math
import sys
import time

import h5py
import numpy as np
import torch
from torch import nn

MODALITIES = 3  # 0 camera, 1 LiDAR, 2 radar


class GruEdge(nn.Module):
    """Per window and modality the masked mean of [latent, offset] and a
    presence flag, a GRU over the last `history_windows` windows, a linear
    head. Positions are normalised by the training set's mean and scale
    (buffers, saved with the model)."""

    history_windows: int

    def __init__(self, latent_dim: int, history: int, hidden: int, mean, scale):
        super().__init__()
        self.history_windows = history
        per = latent_dim + 2
        self.embed = nn.Sequential(nn.Linear(MODALITIES * per, hidden), nn.ReLU())
        self.gru = nn.GRU(hidden, hidden, batch_first=True)
        self.head = nn.Linear(hidden, 3)
        self.register_buffer("mean", torch.as_tensor(mean, dtype=torch.float32))
        self.register_buffer("scale", torch.as_tensor(scale, dtype=torch.float32))

    def features(self, latents, offsets_s, mask):
        # latents [B, L, 3, F, z], offsets_s and mask [B, L, 3, F]
        count = mask.sum(-1, keepdim=True)  # [B, L, 3, 1]
        denom = count.clamp(min=1.0)
        mean_latent = (latents * mask.unsqueeze(-1)).sum(-2) / denom
        mean_offset = (offsets_s * mask).sum(-1, keepdim=True) / denom
        present = (count > 0).to(latents.dtype)
        x = torch.cat([mean_latent, mean_offset, present], dim=-1)  # [B, L, 3, z + 2]
        return x.flatten(2)

    def batch(self, latents, offsets_s, mask):
        h, _ = self.gru(self.embed(self.features(latents, offsets_s, mask)))
        return self.head(h[:, -1]) * self.scale + self.mean  # [B, 3]

    def forward(self, latents, offsets_s, mask):
        # uavsim's call: one window's history, no batch dimension.
        return self.batch(latents.unsqueeze(0), offsets_s.unsqueeze(0), mask.unsqueeze(0))[0]


def read_episode(g, latent_dim):
    """Per window k (1..K): per modality the on-time frames' latents and
    offsets, in capture order; and the truth at each window's end."""
    window_s = float(g.attrs["window_s"])
    truth = np.asarray(g["window_truth_m"], dtype=np.float64)
    f = g["frames"]
    t = np.asarray(f["t_capture_s"])
    on_time = np.asarray(f["on_time"]).astype(bool)
    modality = np.asarray(f["modality"])
    window = np.asarray(f["window"])
    latent = np.asarray(f["latent"], dtype=np.float32)
    if latent.shape[1] != latent_dim:
        raise SystemExit(f"latents of {latent.shape[1]} values, expected {latent_dim}")
    windows = [[[] for _ in range(MODALITIES)] for _ in range(len(truth))]
    for i in np.argsort(t, kind="stable"):
        k = int(window[i])
        if not on_time[i] or k < 1 or k > len(truth):
            continue
        offset = t[i] - (k - 1) * window_s
        windows[k - 1][int(modality[i])].append((latent[i], offset))
    return windows, truth


def samples(episodes, history, latent_dim, frames):
    """Every window that has seen data (as uavsim answers from its first
    window with a frame): the padded history tensors and the truth."""
    xs, os_, ms, ys = [], [], [], []
    for windows, truth in episodes:
        seen = False
        for k in range(len(windows)):
            seen = seen or any(windows[k][m] for m in range(MODALITIES))
            if not seen:
                continue
            lat = np.zeros((history, MODALITIES, frames, latent_dim), np.float32)
            off = np.zeros((history, MODALITIES, frames), np.float32)
            msk = np.zeros((history, MODALITIES, frames), np.float32)
            for l in range(history):
                j = k - (history - 1) + l
                if j < 0:
                    continue  # before the run's first window: padding
                for m in range(MODALITIES):
                    for f, (z, o) in enumerate(windows[j][m][:frames]):
                        lat[l, m, f], off[l, m, f], msk[l, m, f] = z, o, 1.0
            xs.append(lat), os_.append(off), ms.append(msk), ys.append(truth[k])
    return (torch.from_numpy(np.stack(xs)), torch.from_numpy(np.stack(os_)),
            torch.from_numpy(np.stack(ms)), torch.from_numpy(np.stack(ys)).float())


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("data", help="HDF5 file from `uavsim dataset ... --model DIR`")
    ap.add_argument("--out", default="mine.pt", help="TorchScript file to write")
    ap.add_argument("--seconds", type=float, default=60.0, help="training wall time")
    ap.add_argument("--history", type=int, default=10, help="windows the GRU sees (L)")
    ap.add_argument("--hidden", type=int, default=64)
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args()
    torch.manual_seed(a.seed)
    torch.set_num_threads(1)

    with h5py.File(a.data, "r") as h5:
        latent_dim = int(h5.attrs["latent_dim"])
        if latent_dim == 0:
            raise SystemExit(f"{a.data} has no latents: make it with `uavsim dataset --model DIR`")
        names = sorted(h5["episodes"].keys())
        episodes = [read_episode(h5["episodes"][n], latent_dim) for n in names]
    if len(episodes) < 2:
        raise SystemExit("need at least 2 episodes (the last one is held out)")
    frames = max(1, max(len(w[m]) for e, _ in episodes for w in e for m in range(MODALITIES)))
    train = samples(episodes[:-1], a.history, latent_dim, frames)
    test = samples(episodes[-1:], a.history, latent_dim, frames)
    mean = train[3].mean(0)
    scale = train[3].std(0).clamp(min=1.0)
    model = GruEdge(latent_dim, a.history, a.hidden, mean, scale)
    opt = torch.optim.Adam(model.parameters(), lr=3e-3)
    n = train[0].shape[0]
    start, steps = time.monotonic(), 0
    while time.monotonic() - start < a.seconds or steps == 0:
        idx = torch.randint(0, n, (min(64, n),))
        pred = model.batch(train[0][idx], train[1][idx], train[2][idx])
        loss = (((pred - train[3][idx]) / scale) ** 2).mean()
        opt.zero_grad()
        loss.backward()
        opt.step()
        steps += 1
    model.eval()
    with torch.no_grad():
        err = model.batch(*test[:3]) - test[3]
        rmse = math.sqrt(float((err ** 2).sum(1).mean()))
    scripted = torch.jit.script(model)
    scripted.save(a.out)
    counts = [0] * MODALITIES
    on_time = [0] * MODALITIES
    with h5py.File(a.data, "r") as h5:
        for name in names:
            f = h5["episodes"][name]["frames"]
            mod = np.asarray(f["modality"])
            ot = np.asarray(f["on_time"]).astype(bool)
            for m in range(MODALITIES):
                counts[m] += int((mod == m).sum())
                on_time[m] += int(((mod == m) & ot).sum())
    print(json.dumps({
        "episodes": len(episodes),
        "windows": int(sum(len(t) for _, t in episodes)),
        "frames": dict(zip(["camera", "lidar", "radar"], counts)),
        "on_time": dict(zip(["camera", "lidar", "radar"], on_time)),
        "latent_dim": latent_dim,
        "max_frames_per_window": frames,
        "history_windows": a.history,
        "training_samples": n,
        "steps": steps,
        "parameters": sum(p.numel() for p in model.parameters()),
        "held_out_windows": int(test[0].shape[0]),
        "held_out_rmse_m": rmse,
        "out": a.out,
    }))


if __name__ == "__main__":
    sys.exit(main())
