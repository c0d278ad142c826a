"""uavsim.run: one scenario end to end, the results as Python values."""
import json
import os
import shutil
import tempfile

from . import _uavsim
from ._method import split_methods
from ._results import Run
from ._scenario import Scenario


def run(scenario, seed=None, duration=None, methods=None, out=None, force=False, quiet=False,
        record=(), report=None, trace=None, replay=None):
    """Runs a scenario as `uavsim run` does and returns a Run.

    scenario   a file path, a dict or a Scenario (with its .set overrides)
    seed       the scenario's /seed (as --seed); duration: /duration_s (as --duration)
    methods    /pipeline/methods: names ("uavloc", "ekf", ...), TorchScript
               entries (dicts) and uavsim.PythonMethod objects; None: the scenario's
    out        the run directory to write (the same files `uavsim run --out`
               writes, byte for byte, wall times aside); None: a temporary one,
               read and removed (no report drawn)
    force      replace `out` if it exists; quiet: no progress on the terminal
    record     "camera", "lidar", "radar", "mcap" (as --record)
    report     draw report.html (default: when `out` is given)
    trace, replay  a folder for sensing traces (as --trace / --replay)
    Raises ScenarioError for bad input, KeyboardInterrupt on Ctrl-C (nothing
    is left under `out`), and a Python method's own exception.
    """
    s = Scenario(scenario)
    entries, hosted = split_methods(methods)
    extra = []
    if methods is not None:
        extra.append("/pipeline/methods=" + json.dumps(entries))
    if seed is not None:
        if not isinstance(seed, int) or seed < 0:
            raise ValueError("seed is a non-negative integer, got %r" % (seed,))
        extra.append("/seed=%d" % seed)
    if duration is not None:
        if not duration > 0:
            raise ValueError("duration is a positive number of seconds, got %r" % (duration,))
        extra.append("/duration_s=" + json.dumps(duration))
    if isinstance(record, str):
        record = [r for r in record.split(",") if r]
    keep = out is not None
    tmp = None if keep else tempfile.mkdtemp(prefix="uavsim-run-")
    folder = os.fspath(out) if keep else os.path.join(tmp, "run")
    try:
        path, document, overrides = s._args(extra)
        _uavsim.run(path, document, overrides, folder, bool(force), bool(quiet),
                    keep if report is None else bool(report), list(record), trace or "",
                    replay or "", hosted)
        return Run(folder, keep)
    finally:
        if tmp:
            shutil.rmtree(tmp, ignore_errors=True)
