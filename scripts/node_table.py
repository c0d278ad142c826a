#!/usr/bin/python3
"""What the nodes send, setting against setting, in runs of the shipped
scenarios' own flights (docs/nodes.md's tables, issue 72): the twin and the
default city, 20 s, clear / fog 300 m / rain 10 mm/h; per run each
modality's target_sight counts (sends holding the drone of those sent,
frames seeing the drone still sent with the drone) and `ekf` /
`anchor_track` RMSE on the windows every setting answers.

    scripts/node_table.py [--out DIR] [--seeds twin=1 default=7]
                          [--mode NAME=/pointer=value,/pointer=value ...]

Without --mode: the LiDAR background's table (warmup, survey, survey with
the drone gate). Pointers are under /pipeline/preprocess. Example, the
radar's score on top of the survey:

    scripts/node_table.py --out /tmp/radar_score \\
        --mode survey=/lidar/background=survey \\
        --mode score=/lidar/background=survey,/radar/min_peak_snr_db=8

Runs are kept in DIR (default /tmp/node_table) and reused; surveys are
cached under DIR/cache (UAVSIM_CACHE_DIR). About 35 s a run on 2 cores."""
import argparse
import csv
import json
import math
import os
import subprocess

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
UAVSIM = os.path.join(ROOT, "build", "uavsim")
WEATHER = {"clear": [], "fog": ["--set", "/weather/fog_visibility_m=300"],
           "rain": ["--set", "/weather/rain_mm_h=10"]}
LIDAR_MODES = ["warmup=", "survey=/lidar/background=survey",
               "gate=/lidar/background=survey,/lidar/drone_gate=true"]


def parse_mode(text):
    name, _, sets = text.partition("=")
    args = []
    for s in filter(None, sets.split(",")):
        args += ["--set", "/pipeline/preprocess" + s]
    return name, args


def run(a, env, scenario, seed, weather, name, args):
    out = os.path.join(a.out, f"{scenario}_s{seed}_{weather}_{name}")
    if not os.path.exists(os.path.join(out, "metrics.json")):
        subprocess.run([UAVSIM, "run", os.path.join(ROOT, "scenarios", scenario + ".json"),
                        "--out", out, "--quiet", "--seed", str(seed), "--duration", "20", "--set",
                        '/pipeline/methods=["ekf","anchor_track"]'] + WEATHER[weather] + args,
                       check=True, env=env)
    return out


def points(out, name, method=None):
    return {round(float(r["t_s"]), 3): tuple(float(r[k]) for k in ("x_m", "y_m", "z_m"))
            for r in csv.DictReader(open(os.path.join(out, name)))
            if (method is None or r["method"] == method) and r["x_m"] != ""}


def row(outs, mode, truth):
    m = json.load(open(os.path.join(outs[mode], "metrics.json")))
    sight = {k: v["target_sight"] for k, v in m["modalities"].items() if "target_sight" in v}
    text = [f"{k} sends {s['sent_holding_target']}/{s['frames_sent']} seen-sent "
            f"{s['seeing_and_sent']}/{s['frames_seeing_target']}" for k, s in sight.items()]
    for method in ("ekf", "anchor_track"):
        e = {md: points(o, "estimates.csv", method) for md, o in outs.items()}
        common = set(truth).intersection(*e.values())
        rmse = (math.sqrt(sum(math.dist(e[mode][t], truth[t]) ** 2 for t in common) / len(common))
                if common else float("nan"))
        text.append(f"{method} {rmse:.2f} m on {len(common)} (answers {len(e[mode])})")
    return "; ".join(text)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default="/tmp/node_table")
    ap.add_argument("--seeds", nargs="*", default=["mmaud_twin=1", "default=7"],
                    help="SCENARIO=SEED[:SEED...]")
    ap.add_argument("--mode", action="append")
    ap.add_argument("--weather", nargs="*", default=list(WEATHER))
    a = ap.parse_args()
    modes = dict(parse_mode(m) for m in (a.mode or LIDAR_MODES))
    env = dict(os.environ, UAVSIM_CACHE_DIR=os.path.join(a.out, "cache"))
    for spec in a.seeds:
        scenario, _, seeds = spec.partition("=")
        for seed in [int(s) for s in seeds.split(":")]:
            for weather in a.weather:
                outs = {n: run(a, env, scenario, seed, weather, n, args)
                        for n, args in modes.items()}
                truth = points(next(iter(outs.values())), "truth.csv")
                for n in outs:
                    print(f"{scenario} seed {seed} {weather} {n}: {row(outs, n, truth)}",
                          flush=True)


if __name__ == "__main__":
    main()
