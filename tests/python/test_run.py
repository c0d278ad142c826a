"""uavsim.run against `uavsim run`, and Python methods in the loop."""
import os
import re
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest
import uavsim
from conftest import BUILD, DEFAULT, cli, same_run

SECONDS = 2


def test_the_same_run_from_python_and_from_the_command_line(tmp_path):
    a, b = tmp_path / "cli", tmp_path / "py"
    rc, out, err = cli("run", DEFAULT, "--out", a, "--duration", SECONDS, "--seed", 5, "--set",
                       "/links/default/loss/p=0.1", "--quiet")
    assert rc == 0, err
    scenario = uavsim.Scenario(DEFAULT).set("/links/default/loss/p", 0.1)
    run = uavsim.run(scenario, seed=5, duration=SECONDS, out=str(b), quiet=True)
    same_run(str(a), str(b))
    # The Python values are the files' contents.
    assert run.rmse == run.metrics["rmse_m"]
    assert set(run.rmse) == {"uavloc", "uavloc_anchored", "anchor_track", "ekf"}
    truth = np.loadtxt(a / "truth.csv", delimiter=",", skiprows=1)
    assert np.array_equal(run.truth["x_m"], truth[:, 1])
    est = run.estimates["uavloc"]
    assert len(est) > 0 and est.dtype.names == ("t_s", "x_m", "y_m", "z_m")
    assert set(run.packets["status"]) <= {"delivered", "late", "lost"}
    assert "perfect" in run.rate_snr and "snr_db" in run.rate_snr["ekf"].dtype.names


def test_without_out_nothing_is_kept(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    run = uavsim.run(DEFAULT, duration=1, methods=["ekf"], quiet=True)
    assert run.dir is None and list(tmp_path.iterdir()) == []
    assert list(run.rmse) == ["ekf"]


def truth_at(run):
    t, xyz = run.truth["t_s"], np.stack([run.truth[c] for c in ("x_m", "y_m", "z_m")], axis=1)
    return lambda s: np.array([np.interp(s, t, xyz[:, i]) for i in range(3)])


def test_a_python_method_that_returns_the_truth_scores_zero(tmp_path):
    # truth.csv ends a row before the run's end: the reference runs longer.
    reference = uavsim.run(DEFAULT, duration=SECONDS + 1, methods=["ekf"], quiet=True)
    truth = truth_at(reference)
    calls = []

    def oracle(latents, offsets_s, mask, t_end_s):
        calls.append((latents.shape, offsets_s.shape, mask.shape))
        assert latents.dtype == np.float32 and mask.max() <= 1
        return truth(t_end_s)

    run = uavsim.run(DEFAULT, duration=SECONDS, out=str(tmp_path / "r"), quiet=True,
                     methods=["ekf", uavsim.PythonMethod("oracle", oracle, history_windows=4,
                                                         window_time=True)])
    assert run.rmse["oracle"] < 1e-5
    assert len(run.estimates["oracle"]) == len(calls) > 0
    L, M, F, z = calls[0][0]
    assert (L, M) == (4, 3) and z == 16 and calls[0][1] == (L, M, F)
    assert "oracle" in run.rate_snr
    with open(tmp_path / "r" / "report.html") as f:
        assert "oracle (Python, 4 windows)" in f.read()
    # The same flight.
    assert np.array_equal(run.truth, reference.truth[: len(run.truth)])


def test_a_method_that_raises_stops_the_run_and_leaves_nothing(tmp_path):
    def broken(latents, offsets_s, mask):
        raise ZeroDivisionError("my model failed")

    out = tmp_path / "r"
    with pytest.raises(ZeroDivisionError, match="my model failed") as e:
        uavsim.run(DEFAULT, duration=SECONDS, out=str(out), quiet=True,
                   methods=["ekf", uavsim.PythonMethod("broken", broken)])
    assert "broken" in "".join(str(tb.name) for tb in e.traceback)
    assert list(tmp_path.iterdir()) == []


def test_a_method_that_returns_nonsense_is_an_error(tmp_path):
    with pytest.raises(TypeError, match="expected 3 numbers"):
        uavsim.run(DEFAULT, duration=1, quiet=True,
                   methods=[uavsim.PythonMethod("two", lambda *a: [1.0, 2.0])])


class Opaque:
    def __repr__(self):
        return "Opaque(" + "x" * 200 + ")"


# One bad return value per kind: (value, exception, how the message shows it, why it is bad).
BAD_RETURNS = {
    "str": ("abc", TypeError, "str 'abc'", "not numbers"),
    "bytes": (b"1.0", TypeError, "bytes b'1.0'", "not numbers"),
    "wrong_length": ([1.0, 2.0], TypeError, "list [1.0, 2.0]", "2 values"),
    "dict": ({"x": 1, "y": 2, "z": 3}, TypeError, "dict {'x': 1, 'y': 2, 'z': 3}", "not numbers"),
    "object": (Opaque(), TypeError, "Opaque Opaque(" + "x" * 50 + "...", "not numbers"),
    "strings": (["1", "2", "3"], TypeError, "list ['1', '2', '3']", "not numbers"),
    "ragged": ([[1.0, 2.0], [3.0]], TypeError, "list [[1.0, 2.0], [3.0]]", "not numbers"),
    "none_inside": ([1.0, None, 3.0], TypeError, "list [1.0, None, 3.0]", "not numbers"),
    "nan": ([0.0, float("nan"), 0.0], ValueError, "list [0.0, nan, 0.0]", "not finite"),
    "inf": (np.array([np.inf, 0, 0], dtype=np.float32), ValueError,
            "numpy.ndarray array([inf, 0., 0.], dtype=float32)", "not finite"),
}


@pytest.mark.parametrize("kind", BAD_RETURNS)
def test_a_bad_return_value_names_the_method_and_the_window(tmp_path, kind):
    value, error, shown, why = BAD_RETURNS[kind]
    with pytest.raises(error) as e:
        uavsim.run(DEFAULT, duration=1, out=str(tmp_path / "r"), quiet=True,
                   methods=["ekf", uavsim.PythonMethod("bad", lambda *a: value)])
    message = str(e.value)
    assert type(e.value) is error, message
    assert re.fullmatch(re.escape('PythonMethod "bad" returned %s at window ' % shown) + r"\d+" +
                        re.escape(": %s; expected 3 numbers (x, y, z: world ENU metres) or None" % why),
                        message), message
    assert list(tmp_path.iterdir()) == []


def test_three_numbers_in_any_shape_are_a_position():
    answers = [(1, 2, 3), np.array([[1.0], [2.0], [3.0]], dtype=np.float16), [[np.int8(1), 2, 3.5]]]
    calls = []

    def fn(*args):
        calls.append(1)
        return answers[(len(calls) - 1) % len(answers)]

    run = uavsim.run(DEFAULT, duration=1, quiet=True, methods=[uavsim.PythonMethod("shapes", fn)])
    assert len(run.estimates["shapes"]) == len(calls) >= len(answers)


def test_ctrl_c_stops_a_run_and_leaves_nothing(tmp_path):
    script = textwrap.dedent("""
        import sys, uavsim
        print("started", flush=True)
        uavsim.run(sys.argv[1], duration=600, out=sys.argv[2], quiet=True)
    """)
    env = dict(os.environ, PYTHONPATH=os.path.join(BUILD, "python"))
    p = subprocess.Popen([sys.executable, "-c", script, DEFAULT, str(tmp_path / "r")], env=env,
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert p.stdout.readline().strip() == "started"
    # Once the run is under way (its staging folder exists), interrupt it.
    while not list(tmp_path.iterdir()) and p.poll() is None:
        time.sleep(0.05)
    p.send_signal(signal.SIGINT)
    _, err = p.communicate(timeout=120)
    assert p.returncode != 0
    assert "KeyboardInterrupt" in err
    assert list(tmp_path.iterdir()) == []
