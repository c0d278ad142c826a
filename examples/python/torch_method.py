#!/usr/bin/python3
"""A PyTorch model trained in Python runs in the loop as a uavsim.PythonMethod,
without exporting anything.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/torch_method.py --seconds 60

1. uavsim.dataset simulates --episodes training episodes of the scenario with
   the shipped model's encoders (latents as the nodes send them);
2. the GRU edge model of train_gru.py (beside this file) trains on them for
   --seconds of wall time;
3. uavsim.run runs the scenario with `uavloc`, `ekf` and the GRU as method
   "my_gru", called at every window's deadline on the latents that arrived on
   time (the same tensors a TorchScript method gets), and prints each
   method's RMSE as `uavsim run` does.
A GRU trained for a minute on a few episodes is not a good localizer: the
point is the loop, not the figure.
"""
import argparse
import os
import sys
import tempfile
import time

import h5py
import torch
import uavsim

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from train_gru import GruEdge, read_episode, samples  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scenario", default=os.path.join(HERE, "..", "..", "scenarios", "default.json"))
    ap.add_argument("--episodes", type=int, default=8)
    ap.add_argument("--seconds", type=float, default=60.0, help="training wall time")
    ap.add_argument("--history", type=int, default=10)
    ap.add_argument("--duration", type=float, default=30.0, help="simulated seconds of the run")
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args()
    torch.manual_seed(a.seed)
    torch.set_num_threads(1)

    with tempfile.TemporaryDirectory() as tmp:
        data = uavsim.dataset(a.scenario, out=os.path.join(tmp, "data.h5"), episodes=a.episodes,
                              episode_s=20, model="default", quiet=True)
        with h5py.File(data, "r") as h5:
            z = int(h5.attrs["latent_dim"])
            episodes = [read_episode(h5["episodes"][n], z) for n in sorted(h5["episodes"])]
    frames = max(1, max(len(w[m]) for e, _ in episodes for w in e for m in range(3)))
    x, off, mask, y = samples(episodes, a.history, z, frames)
    model = GruEdge(z, a.history, 64, y.mean(0), y.std(0).clamp(min=1.0))
    opt = torch.optim.Adam(model.parameters(), lr=3e-3)
    start, steps = time.monotonic(), 0
    while time.monotonic() - start < a.seconds:
        idx = torch.randint(0, len(x), (min(64, len(x)),))
        loss = (((model.batch(x[idx], off[idx], mask[idx]) - y[idx]) / model.scale) ** 2).mean()
        opt.zero_grad()
        loss.backward()
        opt.step()
        steps += 1
    model.eval()
    print("trained on %d windows of %d episodes, %d steps" % (len(x), len(episodes), steps))

    @torch.no_grad()
    def gru(latents, offsets_s, mask):
        return model(torch.from_numpy(latents), torch.from_numpy(offsets_s),
                     torch.from_numpy(mask)).numpy()

    run = uavsim.run(a.scenario, seed=a.seed, duration=a.duration,
                     methods=["uavloc", "ekf", uavsim.PythonMethod("my_gru", gru, history_windows=a.history)])
    print("RMSE (m): " + "  ".join("%s %.3f" % (m, v) for m, v in run.rmse.items() if v is not None))
    common = run.metrics.get("rmse_common_m", {})
    if common:
        print("over the %d windows every method estimated: %s" % (run.metrics["common_windows"], "  ".join(
            "%s %.3f" % (m, v) for m, v in common.items())))
    print("my_gru estimated %d of %d windows" % (len(run.estimates["my_gru"]), run.metrics["windows"]))


if __name__ == "__main__":
    main()
