"""The other commands from Python: a sweep's tables as arrays."""
import os

import uavsim
from conftest import DEFAULT


def test_a_sweep_from_a_dict(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    spec = {"name": "tiny", "scenario": DEFAULT, "seeds": [1],
            "set": {"/duration_s": 1, "/pipeline/methods": ["ekf"]},
            "parameters": [{"name": "loss", "pointer": "/links/default/loss/p",
                            "values": [0.0, 0.5]}]}
    result = uavsim.sweep(spec, out=str(tmp_path / "s"), quiet=True)
    assert len(result.summary) == 2
    assert list(result.summary["loss"]) == [0.0, 0.5]
    assert result.summary["coverage_ekf"].dtype.kind == "f"
    assert os.path.exists(result.report)
    assert not [f for f in os.listdir(tmp_path) if f.endswith(".json")]


def test_a_python_method_in_a_sweep_of_two_jobs(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    spec = {"name": "py", "scenario": DEFAULT, "seeds": [1, 2], "set": {"/duration_s": 1}}

    def centre(latents, offsets_s, mask):  # a constant: scored like any method
        return [0.0, 0.0, 30.0]

    result = uavsim.sweep(spec, out=str(tmp_path / "s"), jobs=2, quiet=True,
                          methods=["uavloc", uavsim.PythonMethod("centre", centre)])
    assert len(result.summary) == 2
    assert "rmse_centre" in result.summary.dtype.names
    assert all(result.summary["rmse_centre"] > 0)
    assert "rmse_centre_mean" in result.aggregate.dtype.names


def test_a_bad_option_is_a_scenario_error():
    try:
        uavsim.sweep(os.path.join(os.path.dirname(DEFAULT), "sweeps", "loss_weather.json"), bogus=1)
    except uavsim.ScenarioError as e:
        assert e.file is None and "--bogus" in str(e)
    else:
        raise AssertionError("no error")
