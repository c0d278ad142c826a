"""The other commands (`uavsim sweep`, `train`, `dataset`, `report`,
`reproduce`) run in this process: their options as keyword arguments
(--episode-s is episode_s=...; a flag is True), their results as Python
values read from what they wrote."""
import json
import os
import tempfile

from . import _uavsim
from ._method import split_methods
from ._results import read_csv
from ._scenario import Scenario


def _argv(command, positional, options, sets=()):
    argv = ["uavsim", command] + [os.fspath(p) for p in positional]
    for s in sets:
        argv += ["--set", s]
    for key, value in options.items():
        if value is None or value is False:
            continue
        flag = "--" + key.replace("_", "-")
        if value is True:
            argv.append(flag)
        elif isinstance(value, (list, tuple)):
            for v in value:
                argv += [flag, str(v)]
        elif isinstance(value, dict) and key == "set":
            argv += [x for p, v in value.items() for x in ("--set", p + "=" + json.dumps(v))]
        else:
            argv += [flag, str(value)]
    return argv


def command(*argv):
    """Runs `uavsim ARGV...` in this process; raises ScenarioError (exit 2),
    KeyboardInterrupt (Ctrl-C) or RuntimeError (exit 1)."""
    rc = _uavsim.command(["uavsim"] + [str(a) for a in argv])
    if rc != 0:
        raise RuntimeError("uavsim %s: exit code %d" % (" ".join(map(str, argv)), rc))


def _run(command_name, positional, options, sets=(), hosted=None):
    argv = _argv(command_name, positional, options, sets)
    rc = _uavsim.command(argv, hosted or {})
    if rc != 0:
        raise RuntimeError("%s: exit code %d" % (" ".join(argv), rc))


def _scenario_args(scenario, command_name):
    """A scenario as a command's SCENARIO.json and its --set overrides."""
    s = Scenario(scenario)
    if s.path is None:
        raise TypeError("uavsim.%s takes a scenario file (or a Scenario loaded from one)" % command_name)
    return s.path, s.overrides()


class Sweep:
    """A finished sweep folder: summary (a row per point), aggregate (mean and
    95 % interval over the seeds), both structured arrays; report: its page."""

    def __init__(self, folder):
        self.dir = folder
        self.summary = read_csv(os.path.join(folder, "summary.csv"))
        self.aggregate = read_csv(os.path.join(folder, "aggregate.csv"))
        self.report = os.path.join(folder, "report.html")

    def __repr__(self):
        return "Sweep(%s; %d points)" % (self.dir, len(self.summary))


def sweep(spec, out=None, jobs=None, quiet=False, methods=None, **options):
    """`uavsim sweep SPEC` (spec: a file or a dict); options: shard, wait,
    no_traces, keep_traces. methods: every point's /pipeline/methods, names
    and uavsim.PythonMethod objects (their functions run in the points'
    processes, forked from this one). Returns the Sweep."""
    folder = "."
    if isinstance(spec, dict):
        doc = dict(spec)
        doc.setdefault("name", "sweep")
    else:
        path = os.fspath(spec)
        folder = os.path.dirname(path) or "."
        with open(path) as f:
            doc = json.load(f)
        doc.setdefault("name", os.path.splitext(os.path.basename(path))[0])
    entries, hosted = split_methods(methods)
    if methods is not None:
        doc["set"] = dict(doc.get("set", {}), **{"/pipeline/methods": entries})
    tmp = None
    if isinstance(spec, dict) or methods is not None:
        # Beside the spec: its relative paths stay what they were.
        fd, tmp = tempfile.mkstemp(prefix=".uavsim-sweep-", suffix=".json", dir=folder)
        with os.fdopen(fd, "w") as f:
            json.dump(doc, f)
        path = tmp
    name = doc.get("name")
    try:
        _run("sweep", [path], dict(out=out, jobs=jobs, quiet=quiet, **options), hosted=hosted)
    finally:
        if tmp:
            os.unlink(tmp)
    return Sweep(os.fspath(out) if out else os.path.join("runs", name))


def train(scenario, out, quiet=False, **options):
    """`uavsim train SCENARIO --out MODEL` (options: quick, episodes, episode_s,
    jobs, config, config_set=[...], variant, head, ...). Returns the model's
    training_report.json as a dict."""
    path, sets = _scenario_args(scenario, "train")
    _run("train", [path], dict(out=out, quiet=quiet, **options), sets)
    with open(os.path.join(os.fspath(out), "training_report.json")) as f:
        return json.load(f)


def dataset(scenario, out, quiet=False, **options):
    """`uavsim dataset SCENARIO --out FILE.h5` (options: episodes, episode_s,
    seed, jobs, model, force). Returns the file's path (h5py opens it;
    docs/dataset.md gives its schema)."""
    path, sets = _scenario_args(scenario, "dataset")
    _run("dataset", [path], dict(out=out, quiet=quiet, **options), sets)
    return os.fspath(out)


def report(folder, quiet=False):
    """`uavsim report DIR`: redraws a run's, a sweep's or a reproduction's
    report; returns the path of its report.html."""
    _run("report", [folder], dict(quiet=quiet))
    return os.path.join(os.fspath(folder), "report.html")


def reproduce(out=None, quiet=False, **options):
    """`uavsim reproduce` (options: quick, scenario, jobs, seeds, episodes, wait).
    Returns the folder."""
    _run("reproduce", [], dict(out=out, quiet=quiet, **options))
    return out
