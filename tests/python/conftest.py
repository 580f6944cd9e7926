"""Shared fixtures: the build tree (FLATSOS_BUILD_DIR, set by ctest), its models and programs."""
import json
import os
import pathlib

import numpy as np
import pytest

import flatsos


@pytest.fixture(scope="session")
def build_dir():
    path = os.environ.get("FLATSOS_BUILD_DIR")
    if not path:
        pytest.fail("FLATSOS_BUILD_DIR is not set: run the Python tests through ctest (scripts/test.sh)")
    return pathlib.Path(path)


@pytest.fixture(scope="session")
def models_dir(build_dir):
    return build_dir / "share" / "flatsos" / "models"


class Scenario:
    """A model file's 'open_loop' scenario in the units of the Python API (radians, seconds)."""

    def __init__(self, model_file):
        s = json.loads(pathlib.Path(model_file).read_text())["scenarios"]["open_loop"]
        self.q0 = np.radians(s["q0_deg"])
        self.qd0 = np.radians(s.get("qd0_deg_per_s", [0.0] * len(s["q0_deg"])))
        self.a0 = s.get("activations")
        self.target = np.radians(s["target_deg"])
        self.duration = s["duration_s"]
        self.reserves = s["reserves_N"]

    def plan(self, model, **options):
        options.setdefault("preset", "paper")  # the tests' numbers are the paper's configuration's
        return flatsos.plan_open_loop(model, self.q0, self.qd0, self.a0, self.target, self.duration, self.reserves,
                                      **options)


@pytest.fixture(scope="session")
def arm(models_dir):
    return flatsos.Model(str(models_dir / "arm_richter_warner.json")), Scenario(models_dir / "arm_richter_warner.json")


@pytest.fixture(scope="session")
def knee(models_dir):
    """The seated knee: 13 muscles, no flat outputs in its file (the library chooses them)."""
    return flatsos.Model(str(models_dir / "seated_knee_r.json")), Scenario(models_dir / "seated_knee_r.json")
