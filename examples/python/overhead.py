#!/usr/bin/python3
"""What Python costs per window: a PythonMethod's call (its time in the run's
profile, edge/<name>: packing the latents, taking the GIL, the call, reading
the answer) and a BeamEnv step, against the run's own time per window.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/overhead.py --duration 30

Prints one JSON line. The function is trivial (a constant), so what is
measured is the crossing, not a model.
"""
import argparse
import json
import os
import time

import uavsim

HERE = os.path.dirname(os.path.abspath(__file__))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scenario", default=os.path.join(HERE, "..", "..", "scenarios", "default.json"))
    ap.add_argument("--duration", type=float, default=30.0)
    ap.add_argument("--history", type=int, default=10)
    a = ap.parse_args()

    calls = []

    def constant(latents, offsets_s, mask):
        calls.append(latents.shape)
        return (0.0, 0.0, 30.0)

    method = uavsim.PythonMethod("constant", constant, history_windows=a.history)
    run = uavsim.run(a.scenario, duration=a.duration, quiet=True, methods=["uavloc", "ekf", method])
    profile = dict(run.metrics["profile_s"])
    windows = run.metrics["windows"]

    env = uavsim.BeamEnv(a.scenario, duration=a.duration)
    t0 = time.perf_counter()
    obs, info = env.reset(seed=1)
    steps, terminated = 0, False
    t_steps = 0.0
    while not terminated:
        s = time.perf_counter()
        obs, reward, terminated, truncated, info = env.step(None)
        t_steps += time.perf_counter() - s
        steps += 1
    env_wall = time.perf_counter() - t0
    env.close()
    plain = uavsim.run(a.scenario, duration=a.duration, quiet=True)
    print(json.dumps({
        "windows": windows,
        "python_method_calls": len(calls),
        "python_method_ms_per_window": 1e3 * profile["edge/constant"] / len(calls),
        "uavloc_ms_per_window": 1e3 * profile["edge/uavloc"] / windows,
        "latents_shape_last": list(calls[-1]),
        "run_wall_s": run.metrics["wall_s"],
        "env_steps": steps,
        "env_wall_s": env_wall,
        "env_ms_per_step": 1e3 * t_steps / steps,
        "plain_run_wall_s": plain.metrics["wall_s"],
        "plain_run_ms_per_window": 1e3 * plain.metrics["wall_s"] / plain.metrics["windows"],
    }))


if __name__ == "__main__":
    main()
