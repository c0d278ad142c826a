"""Scenarios and errors from Python against the command line's."""
import json
import os

import pytest
import uavsim
from conftest import DEFAULT, cli


def test_version_is_the_command_lines():
    rc, out, _ = cli("--version")
    assert rc == 0
    assert out.split()[1] == uavsim.__version__


def test_resolved_applies_sets_like_the_command_line(tmp_path):
    s = uavsim.Scenario(DEFAULT).set("/links/default/loss/p", 0.2).set("/seed", 7)
    resolved = s.resolved()
    assert resolved["links"]["default"]["loss"]["p"] == 0.2
    assert resolved["seed"] == 7
    rc, out, err = cli("validate", DEFAULT, "--set", "/links/default/loss/p=0.2", "--set", "/seed=7",
                       "--resolved")
    assert rc == 0, err
    assert json.loads(out[out.index("{"):]) == resolved


def test_a_dict_is_a_scenario(monkeypatch):
    with open(DEFAULT) as f:
        doc = json.load(f)
    # Relative paths in a dict resolve against the working directory.
    monkeypatch.chdir(os.path.dirname(DEFAULT))
    assert uavsim.Scenario(doc).resolved()["seed"] == uavsim.Scenario(DEFAULT).resolved()["seed"]


def test_errors_carry_the_command_lines_file_pointer_and_line(tmp_path):
    bad = tmp_path / "bad.json"
    with open(DEFAULT) as f:
        doc = json.load(f)
    doc["links"]["default"]["loss"]["p"] = 1.5
    bad.write_text(json.dumps(doc))
    with pytest.raises(uavsim.ScenarioError) as e:
        uavsim.validate(str(bad))
    rc, _, err = cli("validate", bad)
    assert rc == 2
    assert str(e.value) == err.strip().splitlines()[-1]
    assert e.value.file == str(bad)
    assert e.value.pointer == "/links/default/loss/p"
    assert e.value.message and e.value.message in str(e.value)


def test_a_bad_override_names_its_pointer():
    with pytest.raises(uavsim.ScenarioError) as e:
        uavsim.Scenario(DEFAULT).set("/duration_s", -1).validate()
    assert e.value.pointer == "/duration_s"


def test_a_python_method_is_refused_on_the_command_line(tmp_path):
    with open(DEFAULT) as f:
        doc = json.load(f)
    doc["pipeline"]["methods"] = ["ekf", {"type": "python", "name": "mine"}]
    path = tmp_path / "py.json"
    path.write_text(json.dumps(doc))
    rc, _, err = cli("validate", path)
    assert rc == 2
    assert "/pipeline/methods/1" in err and "Python" in err
    # From Python, with the function given, the same file is valid.
    uavsim.Scenario(str(path)).validate(methods=["ekf", uavsim.PythonMethod("mine", lambda *a: None)])


def test_a_python_methods_entry_is_resolved_and_checked():
    s = uavsim.Scenario(DEFAULT).set("/pipeline/methods", ["ekf", {"type": "python", "name": "m"}])
    assert s.resolved()["pipeline"]["methods"][1] == {"type": "python", "name": "m", "history_windows": 1}
    bad = uavsim.Scenario(DEFAULT).set("/pipeline/methods", [{"type": "python", "name": "ekf"}])
    with pytest.raises(uavsim.ScenarioError) as e:
        bad.resolved()
    assert e.value.pointer == "/pipeline/methods/0/name"
    with pytest.raises(uavsim.ScenarioError) as e:
        uavsim.Scenario(DEFAULT).set("/pipeline/methods", [
            {"type": "python", "name": "m", "history_windows": 0}]).resolved()
    assert e.value.pointer == "/pipeline/methods/0/history_windows"
