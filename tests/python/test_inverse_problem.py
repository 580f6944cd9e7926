"""flatsos.solve_inverse along OpenSim's arm26 tutorial motion, with the muscles MocoInverse's
examples use (DeGroote-Fregly 2016, passive force ignored)."""
import numpy as np
import pytest

import flatsos


def trapezoid(y, t):
    return float(np.sum(0.5 * (y[1:] + y[:-1]) * np.diff(t)))


def test_arm26_shares_the_load_within_the_bounds(models_dir):
    arm26 = models_dir / "opensim" / "arm26"
    model = flatsos.Model(str(arm26 / "arm26.osim"), degroote_muscles=True, ignore_passive_fiber_forces=True)
    motion = str(arm26 / "inverse_kinematics" / "arm26_InverseKinematics.mot")
    r = flatsos.solve_inverse(model, motion)
    assert r["success"], r["message"]
    assert r["effort"] == "excitation_squared" and r["effort_unit"] == "s"
    frames = len(r["time"])
    assert frames == 121
    for key in ("activation", "excitation", "tendon_force"):
        assert r[key].shape == (frames, 6), key
    assert np.all((r["excitation"] >= -1e-6) & (r["excitation"] <= 1 + 1e-6))
    assert r["tendon_force"].min() >= 1.0 - 1e-6  # the default reserves
    # Trapezoid of sum n^2 over the frames, beside the planner's own integral (measured 0.0484).
    squared = trapezoid((r["excitation"] ** 2).sum(axis=1), r["time"])
    assert abs(squared - r["effort_value"]) < 0.02 * r["effort_value"]
    # The linear effort's vertex costs more squared excitation.
    linear = flatsos.solve_inverse(model, motion, effort="paper")
    assert linear["success"], linear["message"]
    assert trapezoid((linear["excitation"] ** 2).sum(axis=1), linear["time"]) > 1.2 * squared


def test_bad_arguments_are_named(models_dir):
    model = flatsos.Model(str(models_dir / "opensim" / "arm26" / "arm26.osim"), degroote_muscles=True)
    motion = str(models_dir / "opensim" / "arm26" / "inverse_kinematics" / "arm26_InverseKinematics.mot")
    with pytest.raises(ValueError, match="effort"):
        flatsos.solve_inverse(model, motion, effort="squared")
    with pytest.raises(ValueError, match="reserves"):
        flatsos.solve_inverse(model, motion, reserves=[1.0, 2.0])
    arm = flatsos.Model(str(models_dir / "arm_richter_warner.json"))
    with pytest.raises(ValueError, match="shoulder"):
        flatsos.solve_inverse(arm, motion)
