"""flatsos.static_optimization along OpenSim's arm26 tutorial motion, against OpenSim's result."""
import numpy as np
import pytest

import flatsos
from flatsos import sto


def test_arm26_as_opensim_computed_it(models_dir):
    arm26 = models_dir / "opensim" / "arm26"
    model = flatsos.Model(str(arm26 / "arm26.osim"), paths="geometry", opensim_2_muscles=True)
    motion = str(arm26 / "inverse_kinematics" / "arm26_InverseKinematics.mot")
    r = flatsos.static_optimization(model, motion)
    assert r["success"], r["message"]
    assert r["strength_rule"] == "opensim2"
    opensim = sto.read_sto(str(arm26 / "static_optimization" / "arm26_StaticOptimization_activation.sto"))
    assert r["activation"].shape == (len(opensim["time"]), 6)
    worst = max(np.max(np.abs(r["activation"][:, j] - opensim[name])) for j, name in enumerate(model.muscles))
    assert worst < 0.02
    assert np.all((r["activation"] >= 0) & (r["activation"] <= 1))
    assert r["reserve_torque"].shape == (len(r["time"]), 2)


def test_efforts_and_bad_arguments(models_dir):
    arm = flatsos.Model(str(models_dir / "arm_richter_warner.json"))
    motion = str(models_dir / "opensim" / "arm26" / "inverse_kinematics" / "arm26_InverseKinematics.mot")
    with pytest.raises(ValueError, match="shoulder"):  # the paper's arm's coordinates are not in arm26's motion
        flatsos.static_optimization(arm, motion)
    arm26 = flatsos.Model(str(models_dir / "opensim" / "arm26" / "arm26.osim"))
    with pytest.raises(ValueError, match="excitation"):
        flatsos.static_optimization(arm26, motion, effort="excitation_squared")
    with pytest.raises(ValueError, match="strength_rule"):
        flatsos.static_optimization(arm26, motion, strength_rule="stiff")
    squared = flatsos.static_optimization(arm26, motion)
    stress = flatsos.static_optimization(arm26, motion, effort="stress_squared")
    assert squared["success"] and stress["success"]
    assert squared["strength_rule"] == "rigid_tendon"
    assert np.max(np.abs(squared["activation"] - stress["activation"])) > 1e-3
