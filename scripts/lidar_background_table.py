#!/usr/bin/python3
"""The table of docs/nodes.md "The LiDAR's background: warm-up or survey":
the twin (seed 1) and the default city (seed 7), 20 s, clear / fog 300 m /
rain 10 mm/h, with lidar.background "warmup", "survey" and "survey" with
the drone gate; per run the LiDAR's and radar's target_sight counts, and
`ekf` / `anchor_track` RMSE on the windows both backgrounds answer.

    scripts/lidar_background_table.py [OUT]    (default /tmp/lidar_background)

About 18 runs of 30-40 s on 2 cores. Surveys are cached under
OUT/cache (UAVSIM_CACHE_DIR)."""
import csv, json, math, os, subprocess, sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
UAVSIM = os.path.join(ROOT, "build", "uavsim")
OUT = sys.argv[1] if len(sys.argv) > 1 else "/tmp/lidar_background"
WEATHER = {"clear": [], "fog": ["--set", "/weather/fog_visibility_m=300"],
           "rain": ["--set", "/weather/rain_mm_h=10"]}
SURVEY = ["--set", "/pipeline/preprocess/lidar/background=survey"]
MODES = {"warmup": [], "survey": SURVEY,
         "gate": SURVEY + ["--set", "/pipeline/preprocess/lidar/drone_gate=true"]}
env = dict(os.environ, UAVSIM_CACHE_DIR=os.path.join(OUT, "cache"))


def run(scenario, seed, weather, mode):
    out = os.path.join(OUT, f"{scenario}_{weather}_{mode}")
    if not os.path.exists(os.path.join(out, "metrics.json")):
        subprocess.run([UAVSIM, "run", os.path.join(ROOT, "scenarios", scenario + ".json"),
                        "--out", out, "--quiet", "--seed", str(seed), "--duration", "20", "--set",
                        '/pipeline/methods=["ekf","anchor_track"]'] + WEATHER[weather] + MODES[mode],
                       check=True, env=env)
    return out


def estimates(out, method):
    return {round(float(r["t_s"]), 3): tuple(float(r[k]) for k in ("x_m", "y_m", "z_m"))
            for r in csv.DictReader(open(os.path.join(out, "estimates.csv")))
            if r["method"] == method and r["x_m"] != ""}


for scenario, seed in (("mmaud_twin", 1), ("default", 7)):
    for weather in WEATHER:
        outs = {mode: run(scenario, seed, weather, mode) for mode in MODES}
        truth = {round(float(r["t_s"]), 3): tuple(float(r[k]) for k in ("x_m", "y_m", "z_m"))
                 for r in csv.DictReader(open(os.path.join(outs["warmup"], "truth.csv")))}
        for mode, out in outs.items():
            m = json.load(open(os.path.join(out, "metrics.json")))
            sight = {k: v["target_sight"] for k, v in m["modalities"].items() if "target_sight" in v}
            text = [f"{k} sends {s['sent_holding_target']}/{s['frames_sent']} seen-sent "
                    f"{s['seeing_and_sent']}/{s['frames_seeing_target']}" for k, s in sight.items()]
            for method in ("ekf", "anchor_track"):
                e = {md: estimates(o, method) for md, o in outs.items()}
                common = set(e["warmup"]) & set(e["survey"]) & set(truth)
                rmse = math.sqrt(sum(math.dist(e[mode][t], truth[t]) ** 2 for t in common)
                                 / len(common))
                text.append(f"{method} {rmse:.2f} m on {len(common)} (answers {len(e[mode])})")
            print(f"{scenario} {weather} {mode}: " + "; ".join(text), flush=True)
