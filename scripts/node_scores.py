#!/usr/bin/python3
"""A node's score and its threshold, chosen on validation flights (issue 72
item 2, docs/nodes.md "A drone or nothing").

Reads a `uavsim dataset` file simulated with the score off, so that every
candidate a node would send is in it. For each modality's score (radar: the
candidate's strongest detection's SNR, `radar.min_peak_snr_db`; LiDAR: its
point count; camera: the ROI's side in pixels), and each threshold t, a
send is kept when its score >= t. A send "holds the drone" as `uavsim
train` counts it (pipeline/training/trainer.cpp ObservationHoldsTarget:
radar, a point within 3 m of the truth; LiDAR 1 m; camera, the bearing
within 1 m of the truth): the truth is used here to choose and to score,
never by a node.

The rule, fixed before the runs were looked at: on the training and
validation flights (the episodes' `part` attribute: the split `uavsim train
--seed` makes; the twin's 9 validation flights hold no rain and 45 radar
sends, too few alone), the largest threshold that keeps at least --keep
(0.9) of the sends holding the drone. Reported per part and per weather: sends, the share holding the
drone, and the share of sends holding the drone that are still sent,
before (no threshold) and after. The test flights are reported, never
used.

    build/uavsim dataset scenarios/mmaud_twin.json --episodes 60 --episode-s 20 \\
        --jobs 2 --set '/pipeline/preprocess/lidar/background="survey"' \\
        --data EP --out twin.h5
    scripts/node_scores.py twin.h5 [--keep 0.9] [--use radar=6.4] [--json OUT.json]
"""
import argparse
import json
import sys

import h5py
import numpy as np

MODALITIES = ("camera", "lidar", "radar")
HOLDS_M = {"camera": 1.0, "lidar": 1.0, "radar": 3.0}
SCORE = {"camera": "roi_side_px", "lidar": "points", "radar": "peak_snr_db"}


def camera_rows(e, truth):
    cam = e["camera"]
    rows = cam["frame"][:]
    eye = cam["eye_left_m"][:]
    u = cam["bearing_left"][:]
    u = u / np.linalg.norm(u, axis=1, keepdims=True)
    d = truth[rows] - eye
    along = np.sum(d * u, axis=1)
    miss = np.linalg.norm(d - along[:, None] * u, axis=1)
    holds = (along > 0) & (miss <= HOLDS_M["camera"]) & (cam["detected"][:] == 1)
    return cam["side_left_px"][:].astype(float), holds


def point_rows(e, truth, modality):
    g = e[modality]
    rows, off, pts = g["frame"][:], g["offsets"][:], g["points"][:]
    score = np.empty(len(rows))
    holds = np.zeros(len(rows), dtype=bool)
    for j, row in enumerate(rows):
        p = pts[off[j]:off[j + 1]]
        if len(p) == 0:
            score[j] = -np.inf
            continue
        holds[j] = np.min(np.linalg.norm(p[:, :3] - truth[row], axis=1)) <= HOLDS_M[modality]
        score[j] = float(np.max(p[:, 4])) if modality == "radar" else float(len(p))
    return score, holds


def read(path):
    """Per modality: arrays score, holds, part, weather over every send."""
    out = {m: {"score": [], "holds": [], "part": [], "weather": []} for m in MODALITIES}
    with h5py.File(path, "r") as f:
        for name, e in f["episodes"].items():
            if "part" not in e.attrs:
                sys.exit(f"{path}: /episodes/{name}: no `part` attribute (made before issue 72's "
                         "dataset; re-export it from its --data file)")
            part, weather = e.attrs["part"], e.attrs["weather"]
            truth = e["frames/truth_m"][:]
            for m in MODALITIES:
                score, holds = (camera_rows(e, truth) if m == "camera" else
                                point_rows(e, truth, m))
                out[m]["score"].append(score)
                out[m]["holds"].append(holds)
                out[m]["part"] += [part] * len(score)
                out[m]["weather"] += [weather] * len(score)
    return {m: {k: (np.concatenate(v) if k in ("score", "holds") else np.array(v))
                for k, v in d.items()} for m, d in out.items()}


def counts(score, holds, t):
    kept = score >= t
    return {"sent": int(kept.sum()), "holding": int((kept & holds).sum()),
            "holding_before": int(holds.sum()), "sent_before": int(len(score))}


def choose(d, keep):
    """The largest threshold keeping >= keep of the non-test sends holding the drone."""
    val = d["part"] != "test"
    s, h = d["score"][val], d["holds"][val]
    if h.sum() == 0:
        return None
    cands = np.unique(s[h])[::-1]  # from the highest score of a send holding the drone down
    for t in cands:
        if (h & (s >= t)).sum() >= keep * h.sum():
            return float(t)
    return float(cands[-1])


def pct(a, b):
    return f"{100.0 * a / b:5.1f}" if b else "    -"


def report(data, keep, use):
    result = {}
    for m in MODALITIES:
        d = data[m]
        chosen = choose(d, keep)
        t = use.get(m, chosen)
        result[m] = {"score": SCORE[m], "chosen": chosen, "threshold": t, "parts": {}}
        print(f"\n{m}: score {SCORE[m]}, chosen {chosen} (keeps >= {keep:.0%} of the training and "
              f"validation sends holding the drone), reported at {t}")
        print("  part        weather   sends  holding%  | after: sends  holding%  still sent%")
        for part in ("train", "validation", "test"):
            for w in ["all"] + sorted(set(d["weather"])):
                sel = (d["part"] == part) & ((d["weather"] == w) if w != "all" else True)
                c = counts(d["score"][sel], d["holds"][sel], -np.inf if t is None else t)
                result[m]["parts"].setdefault(part, {})[w] = c
                print(f"  {part:10s}  {w:8s} {c['sent_before']:6d}  "
                      f"{pct(c['holding_before'], c['sent_before'])}     | {c['sent']:11d}  "
                      f"{pct(c['holding'], c['sent'])}     {pct(c['holding'], c['holding_before'])}")
    return result


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("dataset")
    ap.add_argument("--keep", type=float, default=0.9)
    ap.add_argument("--json")
    ap.add_argument("--use", action="append", default=[], metavar="MODALITY=VALUE",
                    help="report this threshold (the value written in a scenario) instead")
    a = ap.parse_args()
    result = report(read(a.dataset), a.keep, dict((m, float(v)) for m, v in
                                                  (u.split("=") for u in a.use)))
    if a.json:
        with open(a.json, "w") as f:
            json.dump(result, f, indent=1)


if __name__ == "__main__":
    main()
