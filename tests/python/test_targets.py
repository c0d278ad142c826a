"""Several UAVs: roles, truth per target, GOSPA, and the `mtt` tracker's
labelled tracks scored as sets (issue 46)."""
import copy
import itertools
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


def multi_target_scores(run, truth, method, c):
    """GOSPA and OSPA (p = 2; GOSPA's alpha = 2) of the method's single
    estimate against both targets per window, and each target's RMSE where
    the estimate was assigned to it, recomputed from truth.csv and
    estimates.csv: {"rms_m", "ospa_rms_m", "per_target": {id: (rmse, n)}}."""
    e = run.estimates[method]
    assert set(e["track"].tolist()) <= {0}  # one estimate per window: track 0
    est = {round(float(r["t_s"]), 6): np.array([r["x_m"], r["y_m"], r["z_m"]]) for r in e}
    gospa2 = ospa2 = 0.0
    errors = {}
    n = run.metrics["windows"]
    for k in range(1, n + 1):
        t = round(0.2 * k, 6)
        rows = truth[np.abs(truth["t_s"] - t) < 1e-9]
        assert len(rows) == 2
        if t not in est:
            gospa2 += c * c  # both missed: 2 x c^2 / 2
            ospa2 += c * c
            continue
        d = [np.linalg.norm(est[t] - np.array([r["x_m"], r["y_m"], r["z_m"]])) for r in rows]
        i = int(np.argmin(d))
        # One target assigned (the other missed), or none: both missed and a false estimate.
        gospa2 += d[i] ** 2 + c * c / 2 if d[i] < c else 1.5 * c * c
        ospa2 += (min(d[i], c) ** 2 + c * c) / 2
        if d[i] < c:
            errors.setdefault(rows[i]["target"], []).append(d[i] ** 2)
    return {"rms_m": np.sqrt(gospa2 / n), "ospa_rms_m": np.sqrt(ospa2 / n),
            "per_target": {t: (np.sqrt(np.mean(e)), len(e)) for t, e in errors.items()}}


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
        ours = multi_target_scores(run, longer, method, 10.0)
        got = g["methods"][method]
        assert got["rms_m"] == pytest.approx(ours["rms_m"], abs=1e-5)
        assert got["ospa_rms_m"] == pytest.approx(ours["ospa_rms_m"], abs=1e-5)
        assert got["missed_per_window"] >= 1.0
        assert got["cardinality_error"] == 1.0 + (run.metrics["windows"] - len(run.estimates[method])) \
            / run.metrics["windows"]
        for target, (rmse, windows) in ours["per_target"].items():
            assert got["per_target"][target]["windows"] == windows
            assert got["per_target"][target]["rmse_m"] == pytest.approx(rmse, abs=1e-5)


def test_a_distractor_first_makes_the_second_uav_the_target():
    a = uavsim.run(two_uavs(["distractor", "target"]), duration=SECONDS, quiet=True, methods=["ekf"])
    assert "target" not in a.truth.dtype.names
    b = uavsim.run(two_uavs(["target", "distractor"]), duration=SECONDS, quiet=True, methods=["ekf"])
    assert np.allclose(a.truth["z_m"] - b.truth["z_m"], 15.0)


def set_gospa(truths, estimates, c):
    """GOSPA (p = 2, alpha = 2) by brute force over every assignment of
    truths to estimates or to nothing: (gospa^2, {truth index: estimate
    index})."""
    best, best_map = None, None
    options = list(range(len(estimates))) + [None] * len(truths)
    for chosen in itertools.permutations(options, len(truths)):
        used = [j for j in chosen if j is not None]
        if len(used) != len(set(used)):
            continue
        total, mapping = 0.0, {}
        for i, j in enumerate(chosen):
            d = np.linalg.norm(truths[i] - estimates[j]) if j is not None else None
            if d is not None and d < c:
                total += d * d
                mapping[i] = j
            else:
                total += c * c / 2  # missed (a pair at c or beyond is no better)
        total += c * c / 2 * (len(estimates) - len(mapping))  # false
        if best is None or total < best - 1e-12:
            best, best_map = total, mapping
    return best, best_map


def test_mtt_tracks_both_targets_and_is_scored_as_a_set():
    doc = two_uavs(["target", "target"])
    doc["pipeline"]["methods"] = ["mtt", "uavloc_per_track", "ekf"]
    doc["pipeline"]["preprocess"]["max_observations"] = 4
    seconds = 8
    run = uavsim.run(doc, duration=seconds, quiet=True)
    truth = uavsim.run(doc, duration=seconds + 1, quiet=True, methods=["ekf"]).truth
    mtt = run.estimates["mtt"]
    assert "track" in mtt.dtype.names and (mtt["track"] >= 1).all()
    g = run.metrics["gospa"]["methods"]["mtt"]
    c, n = 10.0, run.metrics["windows"]
    gospa2, switches, fragments = 0.0, 0, 0
    last = [None, None]
    assigned_before = [False, False]
    for k in range(1, n + 1):
        t = round(0.2 * k, 6)
        rows = truth[np.abs(truth["t_s"] - t) < 1e-9]
        targets = [np.array([r["x_m"], r["y_m"], r["z_m"]]) for r in rows]
        here = mtt[np.abs(mtt["t_s"] - t) < 1e-9]
        assert len(set(here["track"].tolist())) == len(here)  # a label once per window
        estimates = [np.array([r["x_m"], r["y_m"], r["z_m"]]) for r in here]
        g2, mapping = set_gospa(targets, estimates, c)
        gospa2 += g2
        for i in range(2):
            if i in mapping:
                label = int(here["track"][mapping[i]])
                switches += last[i] is not None and last[i] != label
                fragments += last[i] is not None and not assigned_before[i]
                last[i] = label
            assigned_before[i] = i in mapping
    assert g["rms_m"] == pytest.approx(np.sqrt(gospa2 / n), abs=1e-5)
    assert g["identity_switches"] == switches
    assert g["fragmentations"] == fragments
    # Both targets found: each assigned in the run's second half.
    for target in ("target", "second"):
        assert g["per_target"][target]["windows"] >= n // 2
        assert g["per_target"][target]["rmse_m"] < 1.0
    assert run.rmse["mtt"] is not None
    # uavloc_per_track runs mtt's tracker: its labels in a window are among
    # mtt's (a confirmed track whose network has no estimate yet is left out).
    per_track = run.estimates["uavloc_per_track"]
    assert len(per_track) > 0 and (per_track["track"] >= 1).all()
    for t in set(per_track["t_s"].tolist()):
        ours = set(per_track["track"][np.abs(per_track["t_s"] - t) < 1e-9].tolist())
        assert ours <= set(mtt["track"][np.abs(mtt["t_s"] - t) < 1e-9].tolist())
    assert "method=uavloc_per_track" in run.metrics["uavloc_model"]["extensions"]
    assert "max_observations=4" in run.metrics["uavloc_model"]["extensions"]
