#!/usr/bin/python3
"""RMSE and coverage against uplink packet loss, from Python: a loop of
uavsim.run calls, the curves drawn with matplotlib.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/sweep_loss.py --out loss.png

Each point is the default scenario with /links/default/loss/p set, run for
--duration simulated seconds per seed; coverage is the share of 0.2 s windows
a method estimated (its RMSE covers only those). Prints one line per point.
"""
import argparse
import os

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import uavsim  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scenario", default=os.path.join(HERE, "..", "..", "scenarios", "default.json"))
    ap.add_argument("--loss", type=float, nargs="+", default=[0.0, 0.1, 0.2, 0.3, 0.5])
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--duration", type=float, default=20.0)
    ap.add_argument("--out", default="loss.png")
    a = ap.parse_args()

    rmse, coverage = {}, {}
    for p in a.loss:
        scenario = uavsim.Scenario(a.scenario).set("/links/default/loss/p", p)
        for seed in a.seeds:
            run = uavsim.run(scenario, seed=seed, duration=a.duration, quiet=True)
            windows = run.metrics["windows"]
            for method, value in run.rmse.items():
                rmse.setdefault(method, {}).setdefault(p, []).append(np.nan if value is None else value)
                coverage.setdefault(method, {}).setdefault(p, []).append(
                    len(run.estimates[method]) / windows)
            print("loss %.2f seed %d: %s" % (p, seed, "  ".join(
                "%s %.3f m" % (m, v) for m, v in run.rmse.items() if v is not None)), flush=True)

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 4))
    for method in rmse:
        ax1.plot(a.loss, [np.nanmean(rmse[method][p]) for p in a.loss], "o-", label=method)
        ax2.plot(a.loss, [np.mean(coverage[method][p]) for p in a.loss], "o-", label=method)
    ax1.set(xlabel="uplink packet loss probability", ylabel="RMSE (m)", yscale="log")
    ax2.set(xlabel="uplink packet loss probability", ylabel="coverage (share of windows)", ylim=(0, 1.05))
    ax1.legend()
    ax1.grid(alpha=0.3)
    ax2.grid(alpha=0.3)
    fig.suptitle("%s, %g s per run, seeds %s" % (os.path.basename(a.scenario), a.duration, a.seeds))
    fig.tight_layout()
    fig.savefig(a.out, dpi=120)
    print("wrote", a.out)


if __name__ == "__main__":
    main()
