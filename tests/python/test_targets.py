"""Several UAVs: roles, truth per target and GOSPA (issue 46, its first part)."""
import copy
import json

import numpy as np
import pytest
import uavsim
from conftest import DEFAULT, same_run

SECONDS = 2


def two_uavs(roles):
    """The default scenario with a second UAV orbiting 15 m higher; roles: a
    role per UAV, None to leave the key out."""
    with open(DEFAULT) as f:
        doc = json.load(f)
    second = copy.deepcopy(doc["uavs"][0])
    second["id"] = "second"
    traj = second["trajectory"]
    if "center_m" in traj:
        traj["center_m"][2] += 15.0
    for uav, role in zip([doc["uavs"][0], second], roles):
        if role is not None:
            uav["role"] = role
    doc["uavs"] = [doc["uavs"][0], second]
    doc["pipeline"]["methods"] = ["uavloc", "anchor_track", "ekf"]
    return doc


def test_default_roles_change_nothing(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    implicit = uavsim.run(two_uavs([None, None]), duration=SECONDS, out=str(tmp_path / "a"), quiet=True)
    uavsim.run(two_uavs(["target", "distractor"]), duration=SECONDS, out=str(tmp_path / "b"), quiet=True)
    same_run(str(tmp_path / "a"), str(tmp_path / "b"))
    assert "target" not in implicit.truth.dtype.names
    assert "gospa" not in implicit.metrics
    resolved = uavsim.Scenario(two_uavs([None, None])).resolved()
    assert [u["role"] for u in resolved["uavs"]] == ["target", "distractor"]


def gospa_rms(run, truth, method, c):
    """GOSPA (p = alpha = 2) of the method's single estimate against both
    targets per window, recomputed here from truth.csv and estimates.csv."""
    est = {round(t, 6): np.array([x, y, z]) for t, x, y, z in run.estimates[method].tolist()}
    total = 0.0
    n = run.metrics["windows"]
    for k in range(1, n + 1):
        t = round(0.2 * k, 6)
        rows = truth[np.abs(truth["t_s"] - t) < 1e-9]
        assert len(rows) == 2
        targets = [np.array([r["x_m"], r["y_m"], r["z_m"]]) for r in rows]
        if t not in est:
            total += c * c  # both missed: 2 x c^2 / 2
            continue
        d = min(np.linalg.norm(est[t] - p) for p in targets)
        # One target assigned (the other missed), or none: both missed and a false estimate.
        total += d * d + c * c / 2 if d < c else 1.5 * c * c
    return np.sqrt(total / n)


def test_two_targets_truth_rows_and_gospa():
    run = uavsim.run(two_uavs(["target", "target"]), duration=SECONDS, quiet=True)
    truth = run.truth
    assert truth.dtype.names[:2] == ("t_s", "target")
    assert list(truth["target"][:2]) == ["target", "second"]
    assert len(truth) == 2 * SECONDS * 20
    # truth.csv stops a row before the run's end: the last window's truth
    # from a longer run of the same flights.
    longer = uavsim.run(two_uavs(["target", "target"]), duration=SECONDS + 1, quiet=True,
                        methods=["ekf"]).truth
    assert np.array_equal(longer[: len(truth)], truth)
    g = run.metrics["gospa"]
    assert g["targets"] == 2 and g["c_m"] == 10.0
    for method in ("uavloc", "anchor_track", "ekf"):
        assert g["methods"][method]["rms_m"] == pytest.approx(gospa_rms(run, longer, method, 10.0),
                                                              abs=1e-5)
        assert g["methods"][method]["missed_per_window"] >= 1.0


def test_a_distractor_first_makes_the_second_uav_the_target():
    a = uavsim.run(two_uavs(["distractor", "target"]), duration=SECONDS, quiet=True, methods=["ekf"])
    assert "target" not in a.truth.dtype.names
    b = uavsim.run(two_uavs(["target", "distractor"]), duration=SECONDS, quiet=True, methods=["ekf"])
    assert np.allclose(a.truth["z_m"] - b.truth["z_m"], 15.0)
