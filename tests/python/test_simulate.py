"""Python on a par with the programs: Simbody under given excitations (arrays or a controls file
written and read back), a plan's replay with its tendon forces and excitations, the free joint
path, against the planner and the C++ program."""
import json
import subprocess

import numpy as np
import pytest

import flatsos
import flatsos.sto as sto


@pytest.fixture(scope="module")
def elbow(models_dir):
    model = flatsos.Model(str(models_dir / "elbow_1dof.json"))
    plan = flatsos.plan_open_loop(model, q0=np.radians([20.0]), qd0=[0.0], a0=None, target=np.radians([90.0]),
                                  duration=1.5, reserves=10.0)
    assert plan.status == "solved", plan.message
    return model, plan


def test_a_plans_replay_carries_its_tendon_forces_and_excitations(elbow):
    _, plan = elbow
    run = flatsos.simulate_plan(plan, reports=150)
    planned = plan.sample(run["time"])
    assert run["completed"]
    np.testing.assert_allclose(run["excitation"], planned["excitation"], atol=1e-9)  # what was applied
    np.testing.assert_allclose(run["tendon_force"], planned["tendon_force"], rtol=1e-5, atol=1e-4)
    np.testing.assert_allclose(run["activation"], planned["activation"], atol=1e-7)


def test_given_excitations_drive_simbody_as_the_plans_own_do(elbow, tmp_path):
    model, plan = elbow
    times = np.linspace(0.0, plan.duration, 3001)
    planned = plan.sample(times)
    start = plan.sample([0.0])
    run = flatsos.simulate(model, q0=start["q"][0], qd0=[0.0], a0=start["activation"][0],
                           excitation=(times, planned["excitation"]), duration=plan.duration, accuracy=1e-10,
                           integrator="rkm", reports=150)
    replay = flatsos.simulate_plan(plan, reports=150)
    assert run["completed"]
    # Linear between 3001 samples of the planned excitations: the same motion to a few 1e-4 deg.
    assert np.degrees(np.abs(run["q"] - replay["q"])).max() < 2e-3
    np.testing.assert_allclose(run["tendon_force"], replay["tendon_force"], rtol=1e-3, atol=1e-2)
    # The same excitations through a controls file, written and read back: the same run exactly.
    path = tmp_path / "controls.sto"
    sto.write_controls(model, times, planned["excitation"], path)
    read_time, read_excitation = sto.read_controls(model, path)
    np.testing.assert_array_equal(read_time, times)
    np.testing.assert_array_equal(read_excitation, planned["excitation"])
    from_file = flatsos.simulate(model, q0=start["q"][0], qd0=[0.0], a0=start["activation"][0], excitation=str(path),
                                 duration=plan.duration, accuracy=1e-10, integrator="rkm", reports=150)
    np.testing.assert_array_equal(from_file["q"], run["q"])


def test_simulate_refuses_bad_excitations_naming_them(elbow, tmp_path):
    model, _ = elbow
    with pytest.raises(ValueError, match=r"excitation: expected 2 rows of 3 excitations"):
        flatsos.simulate(model, [0.3], [0.0], [0.1] * 3, (np.array([0.0, 1.0]), np.zeros((2, 2))), 1.0)
    with pytest.raises(ValueError, match=r"excitation: values must lie in \[0, 1\]"):
        flatsos.simulate(model, [0.3], [0.0], [0.1] * 3, (np.array([0.0, 1.0]), np.full((2, 3), 1.5)), 1.0)
    with pytest.raises(ValueError, match="a0: activations must lie in"):
        flatsos.simulate(model, [0.3], [0.0], [0.0] * 3, (np.array([0.0, 1.0]), np.zeros((2, 3))), 1.0)
    with pytest.raises(ValueError, match="no column '/forceset/biceps'"):
        (tmp_path / "bad.sto").write_text("c\nendheader\ntime\tx\n0\t0\n")
        sto.read_controls(model, tmp_path / "bad.sto")


def test_the_free_path_from_python_is_the_programs(elbow, build_dir, models_dir, tmp_path):
    model, prescribed = elbow
    plan = flatsos.plan_open_loop(model, q0=np.radians([20.0]), qd0=[0.0], a0=None, target=np.radians([90.0]),
                                  duration=1.5, reserves=10.0, free_path_spans=6)
    assert plan.status == "solved", plan.message
    assert plan.free_path["optimized"] and plan.cost < prescribed.cost
    assert plan.free_path["prescribed_status"] == "solved"
    assert prescribed.free_path is None
    done = subprocess.run([str(build_dir / "bin" / "arm_open_loop"), "--model", str(models_dir / "elbow_1dof.json"),
                           "--free-path-spans", "6", "--out", str(tmp_path)], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["effort_value"] == pytest.approx(plan.cost, rel=1e-9)
