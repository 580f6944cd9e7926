"""flatsos.track: the controller following OpenSim's arm26 CMC tutorial motion."""
import numpy as np
import pytest

import flatsos


def test_arm26_follows_the_cmc_tutorial_motion(models_dir):
    arm26 = models_dir / "opensim" / "arm26"
    model = flatsos.Model(str(arm26 / "arm26.osim"), opensim_2_muscles=True)
    motion = str(arm26 / "inverse_kinematics" / "arm26_InverseKinematics.mot")
    r = flatsos.track(model, motion)
    assert r["success"], r["message"]
    assert r["plan_failures"] == 0 and r["clamped_samples"] == 0
    rows = len(r["time"])
    assert r["q"].shape == (rows, 2) and r["excitation"].shape == (rows, 6) and r["position_error"].shape == (rows, 2)
    assert np.all(np.degrees(r["rms_error"]) < [0.025, 0.05])
    assert np.all((r["excitation"] >= 0) & (r["excitation"] <= 1))
    # The position errors are the reference's coordinates minus the plant's, at the same times.
    assert np.allclose(np.sqrt(np.mean(r["position_error"] ** 2, axis=0)), r["rms_error"])
    # A plant given apart (here the same model imported again) is what the loop simulates.
    again = flatsos.track(model, motion, plant=flatsos.Model(str(arm26 / "arm26.osim"), opensim_2_muscles=True))
    assert again["success"] and np.allclose(again["rms_error"], r["rms_error"], rtol=1e-6)


def test_squared_excitations_share_the_load_at_less_effort(models_dir):
    # Each plan minimizes the integral of the squared excitations over its horizon (the default):
    # less of it is spent than with the paper's linear effort, the motion followed as closely.
    arm26 = models_dir / "opensim" / "arm26"
    model = flatsos.Model(str(arm26 / "arm26.osim"), opensim_2_muscles=True)
    motion = str(arm26 / "inverse_kinematics" / "arm26_InverseKinematics.mot")
    linear = flatsos.track(model, motion, effort=None)
    squared = flatsos.track(model, motion)  # the default effort
    assert squared["success"], squared["message"]
    assert squared["plan_failures"] == 0 and squared["clamped_samples"] == 0
    assert squared["excitation_squared_integral"] < 0.75 * linear["excitation_squared_integral"]
    assert np.all(np.degrees(squared["rms_error"]) < 0.08)
    # The integral is the one of the excitations returned.
    u2 = np.sum(squared["excitation"] ** 2, axis=1)
    assert np.isclose(np.trapz(u2, squared["time"]), squared["excitation_squared_integral"], rtol=0.05)


def test_bad_arguments(models_dir):
    arm = flatsos.Model(str(models_dir / "arm_richter_warner.json"))
    motion = str(models_dir / "opensim" / "arm26" / "inverse_kinematics" / "arm26_InverseKinematics.mot")
    with pytest.raises(ValueError, match="shoulder"):  # the paper's arm's coordinates are not in arm26's motion
        flatsos.track(arm, motion)
    arm26 = flatsos.Model(str(models_dir / "opensim" / "arm26" / "arm26.osim"))
    with pytest.raises(ValueError, match="unknown effort 'squared'"):
        flatsos.track(arm26, motion, effort="squared")
    with pytest.raises(ValueError, match="weights"):
        flatsos.track(arm26, motion, effort="excitation_squared", weights=[1.0, 2.0])
    with pytest.raises(ValueError, match="tolerance"):
        flatsos.track(arm26, motion, tolerance=0.0)
    with pytest.raises(ValueError, match="plant"):
        flatsos.track(arm26, motion, plant="arm26.osim")
