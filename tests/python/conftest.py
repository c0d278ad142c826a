"""Paths for the Python tests (ctest sets them; run by hand:
PYTHONPATH=build/python UAVSIM_BUILD_DIR=build /usr/bin/python3 -m pytest tests/python)."""
import json
import os
import subprocess

import pytest

SOURCE = os.environ.get("UAVSIM_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
BUILD = os.environ.get("UAVSIM_BUILD_DIR", os.path.join(SOURCE, "build"))
DEFAULT = os.path.join(SOURCE, "scenarios", "default.json")
CLI = os.path.join(BUILD, "uavsim")
WALL_CLOCK = ("wall_s", "realtime_factor", "profile_s", "started_utc")


def cli(*args):
    """`uavsim ARGS...` as a subprocess: (exit code, stdout, stderr)."""
    p = subprocess.run([CLI] + [str(a) for a in args], capture_output=True, text=True)
    return p.returncode, p.stdout, p.stderr


def same_run(a, b):
    """Every file of run directory a is in b, byte for byte, but the
    wall-clock fields of metrics.json and manifest.json and report.html."""
    files_a = sorted(os.path.relpath(os.path.join(d, f), a) for d, _, fs in os.walk(a) for f in fs)
    files_b = sorted(os.path.relpath(os.path.join(d, f), b) for d, _, fs in os.walk(b) for f in fs)
    assert files_a == files_b
    assert len(files_a) > 8
    for f in files_a:
        if f == "report.html":
            continue
        with open(os.path.join(a, f), "rb") as fa, open(os.path.join(b, f), "rb") as fb:
            da, db = fa.read(), fb.read()
        if f in ("metrics.json", "manifest.json"):
            ja, jb = json.loads(da), json.loads(db)
            for k in WALL_CLOCK:
                ja.pop(k, None), jb.pop(k, None)
            assert ja == jb, f
        else:
            assert da == db, f


@pytest.fixture
def default_scenario():
    return DEFAULT
