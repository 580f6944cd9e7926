"""Messages a new user met: each names the field and the problem (issue: the front door)."""
import json
import os
import pathlib
import subprocess
import warnings

import numpy as np
import pytest

import flatsos

SOURCE_DIR = pathlib.Path(__file__).resolve().parents[2]
BUILD_DIR = pathlib.Path(os.environ.get("FLATSOS_BUILD_DIR", SOURCE_DIR / "build"))
ARM = SOURCE_DIR / "models" / "arm_richter_warner.json"
ELBOW = SOURCE_DIR / "models" / "elbow_posture_dependent.json"  # elbow range [0, 2.5] rad, a soft stop beyond


def hard_stop_elbow():
    """The elbow whose range ends in a hard stop: without its limit torque."""
    model = json.loads(ELBOW.read_text())
    del model["joints"][0]["limit_torque"]
    return flatsos.Model.from_json(json.dumps(model))


def plan(model, q0, target):
    return flatsos.plan_open_loop(model, q0=q0, qd0=np.zeros(len(q0)), a0=None, target=target, duration=1.0,
                                  reserves=10.0)


def test_a_start_in_degrees_is_reported_as_the_start_not_the_target():
    with pytest.raises(ValueError, match=r"^start joint angles \(q0\): .*are the angles in radians\?"):
        plan(flatsos.Model(str(ARM)), q0=[0.0, 10.0], target=np.radians([90.0, 0.0]))


@pytest.mark.parametrize("q0, target, field", [(3.0, 1.0, r"start joint angles \(q0\)"), (1.0, 2.6, "target joint angles")])
def test_a_start_or_target_outside_a_joints_range_names_the_joint_and_its_range(q0, target, field):
    with pytest.raises(ValueError, match=field + r": joint 'elbow' at [0-9.]+ deg is outside its range \[0, 143.239\] deg"):
        plan(hard_stop_elbow(), q0=[q0], target=[target])


def test_the_range_is_inclusive_and_a_soft_stop_may_be_pressed_into():
    assert plan(hard_stop_elbow(), q0=[1.0], target=[2.5]).status == "solved"
    assert plan(flatsos.Model(str(ELBOW)), q0=[1.0], target=[2.55]).status == "solved"


def heavy_model_text(path=ARM):
    model = json.loads(path.read_text())
    model["bodies"][0]["mass_kg"] = 1500.0
    return json.dumps(model)


def test_plausibility_warnings_come_with_the_model_before_any_plan():
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        model = flatsos.Model.from_json(heavy_model_text())
    messages = [str(w.message) for w in caught if issubclass(w.category, UserWarning)]
    assert any("mass_kg: 1500 kg is above 300 kg" in m for m in messages), messages
    assert model.warnings == messages


def run(program, *args, cwd):
    return subprocess.run([str(BUILD_DIR / "bin" / program), *args], capture_output=True, text=True, cwd=cwd)


def test_a_program_prints_the_models_warnings_even_when_the_task_then_fails(tmp_path):
    # A 1500 kg forearm: no rest state at the start (the task fails), yet the warning says why.
    (tmp_path / "heavy.json").write_text(heavy_model_text(SOURCE_DIR / "models" / "elbow_1dof.json"))
    done = run("arm_open_loop", "--model", "heavy.json", "--out", "out", cwd=tmp_path)
    assert done.returncode == 1
    assert "arm_open_loop: warning: bodies[0] 'forearm'.mass_kg: 1500 kg" in done.stderr
    assert done.stderr.index("warning:") < done.stderr.index("error:")


@pytest.mark.parametrize("option, value, bound", [("--duration-s", "0", "> 0"), ("--pieces", "-1", ">= 0")])
def test_a_number_out_of_bounds_says_the_bound_and_the_value(tmp_path, option, value, bound):
    done = run("arm_open_loop", option, value, "--out", "out", cwd=tmp_path)
    assert done.returncode == 2
    assert f"{option}: must be {bound} (got {value})" in done.stderr, done.stderr
    assert len(done.stderr) < 300, done.stderr
