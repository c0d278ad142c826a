#!/usr/bin/python3
"""Step the run window by window (uavsim.BeamEnv) with a naive beam policy
and compare its downlink rate with the beams steered by the `ekf` and by the
true position (`perfect`).

    PYTHONPATH=build/python /usr/bin/python3 examples/python/beam_env.py --duration 20

The naive policy points the beam at the centroid of the point detections
(LiDAR and radar geometric anchors) that reached the edge in the window, and
keeps its last direction when none did. Rewards are the window's rate at
--snr-db (bit/s/Hz).
"""
import argparse
import os

import numpy as np
import uavsim

HERE = os.path.dirname(os.path.abspath(__file__))


class CentroidPolicy:
    def __init__(self):
        self.last = None

    def __call__(self, obs):
        a = obs["arrivals"]
        points = a["anchor_origin"][a["anchor_kind"] == 1]
        if len(points):
            self.last = points.mean(axis=0) - obs["base_station"]
        return self.last  # None before the first detection: the ekf's beam


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scenario", default=os.path.join(HERE, "..", "..", "scenarios", "default.json"))
    ap.add_argument("--duration", type=float, default=20.0)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--snr-db", type=float, default=10.0)
    a = ap.parse_args()

    policy = CentroidPolicy()
    with uavsim.BeamEnv(a.scenario, snr_db=a.snr_db, steer_by="ekf", duration=a.duration) as env:
        obs, info = env.reset(seed=a.seed)
        rewards, ekf, perfect = [], [], []
        terminated = False
        while not terminated:
            rates = info["rates"]
            obs, reward, terminated, truncated, info = env.step(policy(obs))
            rewards.append(reward)
            ekf.append(rates.get("ekf", 0.0))
            perfect.append(rates["perfect"])
    print("%d windows at %.0f dB SNR, mean rate (bit/s/Hz): naive centroid %.3f, ekf %.3f, perfect %.3f"
          % (len(rewards), a.snr_db, np.mean(rewards), np.mean(ekf), np.mean(perfect)))


if __name__ == "__main__":
    main()
