"""uavsim from Python: scenarios, runs, sweeps and results as Python values,
Python functions as methods in the loop, and a step-by-step environment.

    import uavsim
    run = uavsim.run("scenarios/default.json", seed=3, duration=30)
    print(run.rmse)                 # {method: RMSE in metres}, as `uavsim run` prints
    run.estimates["ekf"]["x_m"]     # NumPy arrays with named fields

README.md ("From Python") and examples/python/ show more.
"""
from ._uavsim import __version__, git_hash
from ._errors import ScenarioError
from ._scenario import Scenario, load, validate
from ._method import PythonMethod
from ._results import Run, read_csv
from ._run import run
from ._commands import Sweep, sweep, train, dataset, report, reproduce, command
from ._env import BeamEnv

__all__ = ["__version__", "git_hash", "ScenarioError", "Scenario", "load", "validate",
           "PythonMethod", "Run", "read_csv", "run", "Sweep", "sweep", "train", "dataset",
           "report", "reproduce", "command", "BeamEnv"]
