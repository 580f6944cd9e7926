"""OpenSim models as downloaded: flatsos.Model opens an .osim as it opens a JSON model."""
import numpy as np
import pytest

import flatsos


def test_an_osim_file_is_a_model_that_plans(models_dir):
    model = flatsos.Model(str(models_dir / "opensim" / "Tug_of_War_Millard.osim"))
    assert model.joint_types == ["slider"]
    assert model.muscles == ["RightMuscle", "LeftMuscle"]
    assert model.coordinates == ["block_tz"]
    # 4 cm: with the file's Millard curves no activation holds the block beyond 4.23 cm.
    plan = flatsos.plan_open_loop(model, [0.0], [0.0], None, [0.04], 1.0, 10.0)
    assert plan.status == "solved", plan.message
    back = flatsos.plan_open_loop(model, [0.04], [0.0], None, [0.0], 1.0, 10.0)
    assert back.status == "solved", back.message


def test_geometric_paths_and_opensim_2_muscles_are_asked_by_keyword(models_dir):
    osim = str(models_dir / "opensim" / "Tug_of_War_Millard.osim")
    assert flatsos.Model(osim, paths="geometry").muscles == ["RightMuscle", "LeftMuscle"]
    with pytest.raises(ValueError, match="paths"):
        flatsos.Model(osim, paths="straight")
    with pytest.raises(ValueError, match=r"\.osim"):
        flatsos.Model(str(models_dir / "arm_richter_warner.json"), paths="geometry")
    with pytest.raises(ValueError, match="opensim_2_muscles"):
        flatsos.Model(str(models_dir / "arm_richter_warner.json"), opensim_2_muscles=True)


def test_degroote_muscles_replace_the_files_as_moco_does(models_dir):
    osim = str(models_dir / "opensim" / "Tug_of_War_Millard.osim")
    model = flatsos.Model(osim, degroote_muscles=True, ignore_passive_fiber_forces=True)
    assert model.muscles == ["RightMuscle", "LeftMuscle"]
    plan = flatsos.plan_open_loop(model, [0.0], [0.0], None, [0.02], 1.0, 10.0)
    assert plan.status == "solved", plan.message
    with pytest.raises(ValueError, match="degroote_fregly2016_muscles"):
        flatsos.Model(osim, ignore_passive_fiber_forces=True)
    with pytest.raises(ValueError, match="exclude each other"):
        flatsos.Model(osim, degroote_muscles=True, opensim_2_muscles=True)
    with pytest.raises(ValueError, match="degroote_muscles"):
        flatsos.Model(str(models_dir / "arm_richter_warner.json"), degroote_muscles=True)


def test_arm26_as_downloaded_plans_15_to_90_deg_and_simbody_replays_it(models_dir):
    # The shoulder is held at 0 by the biceps against the triceps (arm26 has no deltoid); TRIlat
    # and TRImed share moment arms and strength, a tie the planner breaks.
    model = flatsos.Model(str(models_dir / "opensim" / "arm26" / "arm26.osim"))
    plan = flatsos.plan_open_loop(model, np.radians([0.0, 15.0]), [0.0, 0.0], None, np.radians([0.0, 90.0]), 1.0, 10.0)
    assert plan.status == "solved", plan.message
    sim = flatsos.simulate_plan(plan)
    planned = plan.sample(sim["time"])
    assert np.degrees(np.abs(planned["q"] - sim["q"]).max()) < 1e-4  # measured 2.5e-8 deg
    assert planned["excitation"].min() >= -1e-6 and planned["excitation"].max() <= 1 + 1e-6


def test_arm26_as_downloaded_is_controlled_to_90_deg(models_dir):
    # No flat outputs serve OpenSim's shoulder range (every E turns C(q) singular or a tendon
    # force negative somewhere); the controller gets flat outputs over the region its task visits.
    model = flatsos.Model(str(models_dir / "opensim" / "arm26" / "arm26.osim"))
    assert model.coordinates == ["r_shoulder_elev", "r_elbow_flex"]
    q0, target = np.radians([0.0, 15.0]), np.radians([0.0, 90.0])
    run = flatsos.run_receding_horizon(model, q0, target, 2.0)
    assert run["success"], run["message"]
    assert np.degrees(np.abs(run["q"][-1] - target)).max() < 1.0
    assert run["plan_failures"] == 0


def test_the_tug_of_wars_block_is_held_against_a_20_N_push(models_dir):
    model = flatsos.Model(str(models_dir / "opensim" / "Tug_of_War_Millard.osim"))
    target = [0.02]  # m
    push = [(0.0, [0.0]), (1.0, [20.0])]  # N along the slider from 1 s on
    quiet = flatsos.run_receding_horizon(model, [0.0], target, 3.0)
    pushed = flatsos.run_receding_horizon(model, [0.0], target, 3.0, disturbance=push)
    assert quiet["success"] and pushed["success"], pushed["message"]
    after = pushed["time"] >= 1.0
    moved_m = np.abs(pushed["q"][after, 0] - quiet["q"][after, 0]).max()
    assert 1e-3 < moved_m < 5e-3  # the push moves the block, the controller takes it back
    assert abs(pushed["q"][-1, 0] - target[0]) < 1e-3
    for bad in ([(0.0, [1.0, 2.0])], [(0.0,)], [("soon", [1.0])], [], 3.0, [(1.0, [1.0]), (0.5, [2.0])]):
        with pytest.raises(ValueError, match="disturbance"):
            flatsos.run_receding_horizon(model, [0.0], target, 1.0, disturbance=bad)
