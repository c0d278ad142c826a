#!/usr/bin/env python3
"""LiDAR points a scan within 25 m of the sensor, per weather (NOTES.md,
2026-12-04, the LiDAR's fog echoes).

Runs `build/uavsim run scenarios/default.json --duration 2.5 --record lidar`
once per weather and prints the mean, over the recorded scans, of the points
of frames/lidar/*.ply within 25 m of the LiDAR's position.

  scripts/lidar_near_returns.py OUT_DIR [fog:V ...] [rain:R ...]
  (no weathers: clear, fog 50 100 200 300 1000 2000 m, rain 5 25 mm/h)
"""
import glob
import json
import math
import struct
import subprocess
import sys


def near_points(ply_path, origin, radius_m=25.0):
    data = open(ply_path, "rb").read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    lines = data[:end].decode().splitlines()
    n = int(next(l for l in lines if l.startswith("element vertex")).split()[2])
    stride = 4 * sum(1 for l in lines if l.startswith("property"))
    return sum(
        math.dist(struct.unpack_from("<3f", data, end + stride * k), origin) < radius_m
        for k in range(n))


def main():
    out = sys.argv[1]
    weathers = sys.argv[2:] or (["clear"] + [f"fog:{v}" for v in (50, 100, 200, 300, 1000, 2000)]
                                + ["rain:5", "rain:25"])
    scenario = json.load(open("scenarios/default.json"))
    lidar = next(n for n in scenario["nodes"] if n["sensor"]["type"] == "lidar")
    origin = tuple(lidar["sensor"]["pose"]["position_m"])
    for w in weathers:
        kind, _, value = w.partition(":")
        sets = {"fog": ["--set", f"/weather/fog_visibility_m={value}"],
                "rain": ["--set", f"/weather/rain_mm_h={value}"]}.get(kind, [])
        run_dir = f"{out}/{w.replace(':', '_')}"
        subprocess.run(["build/uavsim", "run", "scenarios/default.json", "--duration", "2.5",
                        "--record", "lidar", "--out", run_dir] + sets,
                       check=True, stdout=subprocess.DEVNULL)
        counts = [near_points(p, origin) for p in sorted(glob.glob(f"{run_dir}/frames/lidar/*.ply"))]
        print(f"{w}: {len(counts)} scans, mean {sum(counts) / len(counts):.0f} points within 25 m")


if __name__ == "__main__":
    main()
