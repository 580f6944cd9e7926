"""A seeded fuzz of the Python API (issue: a controller to trust in real time): the main calls
with one argument at a time made hostile (zero, negative, huge, NaN, infinite, a wrong size, a
wrong type), and model files made hostile value by value. The documented failures are the only
ones allowed: ValueError or TypeError naming the problem, or RuntimeError for a start no rest
state holds. A crash fails the suite, and a result that says it succeeded carries no NaN."""
import copy
import json

import numpy as np
import pytest

import flatsos

HOSTILE = [0, -1, -1e300, 1e300, float("nan"), float("inf"), -float("inf"), [], [[1.0]], [1.0] * 7, "x", None,
           {"a": 1}, 10 ** 30]
ALLOWED = (ValueError, TypeError, RuntimeError)


def finite_when_successful(result):
    if not (isinstance(result, dict) and (result.get("success") or result.get("completed"))):
        return
    for key, value in result.items():
        if isinstance(value, np.ndarray) and value.dtype.kind == "f":
            assert np.isfinite(value).all(), f"'{key}' holds a non-finite value in a successful result"


def constant_excitation(muscles):
    return np.array([0.0, 1.0]), np.full((2, muscles), 0.3)


def calls(model):
    """(name, function, positional arguments, keyword arguments) of the calls fuzzed, each valid."""
    n, m = len(model.joints), len(model.muscles)
    q0, target = np.radians([30.0] * n), np.radians([60.0] * n)
    return [
        ("simulate", flatsos.simulate, [model, q0, [0.0] * n, [0.2] * m, constant_excitation(m), 0.2],
         {"reports": 20, "max_steps": 2000}),  # a huge duration ends at the step limit
        ("run_receding_horizon", flatsos.run_receding_horizon, [model, q0, target, 0.2],
         {"noise_deg": 0.1, "measurement_delay": 0.01, "actuation_delay": 0.01, "deadline": 1.0}),
        ("plan_open_loop", flatsos.plan_open_loop, [model, q0, [0.0] * n, None, target, 1.0, 1.0],
         {"preset": "paper"}),
    ]


def test_hostile_arguments_raise_value_or_type_errors_only(models_dir):
    model = flatsos.Model(str(models_dir / "elbow_1dof.json"))
    rng = np.random.default_rng(1)
    tried = 0
    for name, function, args, kwargs in calls(model):
        finite_when_successful(function(*args, **kwargs))  # the valid call works
        slots = [("arg", i) for i in range(1, len(args))] + [("kw", k) for k in kwargs]
        for kind, slot in slots:
            for hostile in rng.permutation(len(HOSTILE))[:6]:
                a, kw = list(args), dict(kwargs)
                if kind == "arg":
                    a[slot] = copy.deepcopy(HOSTILE[hostile])
                else:
                    kw[slot] = copy.deepcopy(HOSTILE[hostile])
                try:
                    finite_when_successful(function(*a, **kw))
                except ALLOWED as error:
                    assert str(error), f"{name}: an empty message for {slot} = {HOSTILE[hostile]!r}"
                tried += 1
    assert tried > 60


def hostile_model_texts(text, count, seed):
    """The model file with one value made hostile, `count` times (a number, a string, a list or a
    key), as tests/fuzz/fuzz_model_structure.cpp does to files in C++."""
    rng = np.random.default_rng(seed)
    for _ in range(count):
        document = json.loads(text)
        values = []

        def collect(value, parent, key):
            values.append((parent, key))
            children = value.items() if isinstance(value, dict) else enumerate(value) if isinstance(value, list) else []
            for k, child in children:
                collect(child, value, k)

        collect(document, None, None)
        parent, key = values[1 + rng.integers(len(values) - 1)]
        value = parent[key]
        if isinstance(value, list) and value and rng.random() < 0.5:
            parent[key] = value[:-1] if rng.random() < 0.5 else value + value[:1]
        elif isinstance(value, dict) and value and rng.random() < 0.5:
            del value[list(value)[rng.integers(len(value))]]
        else:
            parent[key] = copy.deepcopy(HOSTILE[rng.integers(len(HOSTILE))])
        yield json.dumps(document).replace("NaN", '"NaN"').replace("Infinity", '"Infinity"')


def test_hostile_model_files_are_refused_with_a_value_error_or_load(models_dir):
    text = (models_dir / "elbow_1dof.json").read_text()
    loaded = refused = 0
    for hostile in hostile_model_texts(text, 300, seed=2):
        try:
            model = flatsos.Model.from_json(hostile, source="fuzzed")
        except ValueError as error:
            assert str(error)
            refused += 1
            continue
        loaded += 1
        try:  # a model that loads may still hold no equilibrium at the start: a ValueError saying so
            finite_when_successful(flatsos.simulate(model, [0.5] * len(model.joints), [0.0] * len(model.joints),
                                                    [0.2] * len(model.muscles), constant_excitation(len(model.muscles)),
                                                    0.05, reports=5, max_steps=2000))
        except ALLOWED as error:
            assert str(error)
    assert refused > 50 and loaded > 20, (refused, loaded)
