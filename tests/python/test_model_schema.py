"""docs/model.schema.json, the JSON Schema editors use: every shipped model and every model the
writer produces (OpenSim imports included) validates, and it refuses what the loader refuses."""
import json
import pathlib

import pytest

import flatsos

jsonschema = pytest.importorskip("jsonschema", reason="python3-jsonschema (scripts/install_deps.sh installs it)")

SOURCE_DIR = pathlib.Path(__file__).resolve().parents[2]
SCHEMA = json.loads((SOURCE_DIR / "docs" / "model.schema.json").read_text())
VALIDATOR = jsonschema.Draft7Validator(SCHEMA)


def errors(model):
    return [f"{'/'.join(map(str, e.path))}: {e.message}" for e in VALIDATOR.iter_errors(model)]


def test_the_schema_is_a_valid_draft_7_schema():
    jsonschema.Draft7Validator.check_schema(SCHEMA)


@pytest.mark.parametrize("path", sorted((SOURCE_DIR / "models").glob("*.json")), ids=lambda p: p.name)
def test_every_shipped_model_validates(path):
    assert errors(json.loads(path.read_text())) == []


@pytest.mark.parametrize("osim", ["arm26/arm26.osim", "Tug_of_War_Millard.osim"])
def test_what_the_writer_makes_of_an_opensim_model_validates(osim):
    model = flatsos.Model(str(SOURCE_DIR / "models" / "opensim" / osim))
    written = json.loads(model.to_json())
    assert errors(written) == []
    if "Millard" in osim:
        assert any("millard2012_curves" in m for m in written["muscles"])  # the curves are covered


@pytest.mark.parametrize("edit, where", [
    (lambda m: m["muscles"][0].update(colour=1), "muscles/0"),                 # an unknown key
    (lambda m: m["joints"][0].pop("parent"), "joints/0"),                      # a missing field
    (lambda m: m["joints"][0].update(type="ball"), "joints/0/type"),           # a type the loader lacks
    (lambda m: m["muscles"][0].update(path={"coordinates": ["elbow"], "order": 1, "coefficients": [0.3, -0.02]}),
     "muscles/0"),                                                             # a path and constant arms both
])
def test_the_schema_refuses_what_the_loader_refuses(edit, where):
    model = json.loads((SOURCE_DIR / "models" / "elbow_1dof.json").read_text())
    edit(model)
    found = errors(model)
    assert any(e.startswith(where) for e in found), found
    with pytest.raises(ValueError):
        flatsos.Model.from_json(json.dumps(model))
