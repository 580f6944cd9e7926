"""flatsos.simulate_plan: what the C++ program simulates from the same inputs, and the plan."""
import subprocess

import numpy as np
import pytest

import flatsos
from flatsos.sto import read_sto


def test_the_simulation_is_the_cpp_programs_and_follows_the_plan(arm, build_dir, models_dir, tmp_path):
    model, scenario = arm
    plan = scenario.plan(model)
    sim = flatsos.simulate_plan(plan)
    assert sim["finite"] and sim["message"] == ""
    assert sim["q"].shape == (301, 2) and sim["activation"].shape == (301, 6)
    program = subprocess.run([str(build_dir / "bin" / "arm_open_loop"), "--model",
                              str(models_dir / "arm_richter_warner.json"), "--out", str(tmp_path)],
                             capture_output=True, text=True)
    assert program.returncode == 0, program.stderr
    table = read_sto(tmp_path / "simulation.sto")
    np.testing.assert_allclose(sim["time"], table["time"], atol=1e-12)
    for i, joint in enumerate(model.joints):
        column = next(label for label in table if label.startswith(f"/jointset/{joint}/") and label.endswith("/value"))
        assert np.degrees(np.abs(sim["q"][:, i] - table[column]).max()) < 1e-9
    for j, muscle in enumerate(model.muscles):
        assert np.abs(sim["activation"][:, j] - table[f"/forceset/{muscle}/activation"]).max() < 1e-9
    # Planned vs simulated (measured: 1.7e-7 deg, activations 6e-10).
    planned = plan.sample(sim["time"])
    assert np.degrees(np.abs(planned["q"] - sim["q"]).max()) < 1e-5
    assert np.abs(planned["activation"] - sim["activation"]).max() < 1e-6


def test_other_integrators_and_bad_options(arm):
    model, scenario = arm
    plan = scenario.plan(model)
    bdf = flatsos.simulate_plan(plan, integrator="bdf", accuracy=1e-8, reports=30)
    assert bdf["q"].shape == (31, 2)
    np.testing.assert_allclose(bdf["q"][-1], scenario.target, atol=np.radians(0.05))
    with pytest.raises(ValueError, match="unknown integrator 'euler'"):
        flatsos.simulate_plan(plan, integrator="euler")
    with pytest.raises(ValueError, match="accuracy"):
        flatsos.simulate_plan(plan, accuracy=0.5)
    with pytest.raises(ValueError, match="reports"):
        flatsos.simulate_plan(plan, reports=0)
    infeasible = scenario.plan(model, torque_pieces=1, torque_degree=0)
    with pytest.raises(ValueError, match="nothing to simulate"):
        flatsos.simulate_plan(infeasible)
