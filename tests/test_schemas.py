"""schemas/ is generated from the pydantic models; files in the repo must follow it."""

from __future__ import annotations

import json

import jsonschema
import pytest

from rigidid import api
from rigidid.jsonout import result_to_dict
from rigidid.schemas import schema_texts

from .conftest import PAPER, ROOT, SAMPLES

SCHEMAS = ROOT / "schemas"


@pytest.mark.parametrize("name", sorted(schema_texts()))
def test_committed_schema_matches_models(name: str) -> None:
    committed = (SCHEMAS / name).read_text(encoding="utf-8")
    assert committed == schema_texts()[name], f"schemas/{name} is stale: run python -m rigidid.schemas schemas"


def _validator(name: str) -> jsonschema.Draft202012Validator:
    return jsonschema.Draft202012Validator(json.loads((SCHEMAS / name).read_text()))


@pytest.mark.parametrize("path", sorted(SAMPLES.glob("*/layout.json")), ids=lambda p: p.parent.name)
def test_sample_layouts_follow_the_schema(path: object) -> None:
    _validator("layout.schema.json").validate(json.loads(path.read_text()))  # type: ignore[attr-defined]


@pytest.mark.parametrize("path", sorted(SAMPLES.glob("*/body.json")), ids=lambda p: p.parent.name)
def test_sample_bodies_follow_the_schema(path: object) -> None:
    _validator("body.schema.json").validate(json.loads(path.read_text()))  # type: ignore[attr-defined]


@pytest.mark.parametrize("path", sorted(SAMPLES.glob("*/mounts.json")), ids=lambda p: p.parent.name)
def test_sample_mounts_follow_the_schema(path: object) -> None:
    _validator("mounts.schema.json").validate(json.loads(path.read_text()))  # type: ignore[attr-defined]


@pytest.mark.filterwarnings("ignore::rigidid.errors.PhysicalPlausibilityWarning")
def test_result_follows_the_schema() -> None:
    data = result_to_dict(api.identify(PAPER / "layout.json", PAPER / "modes.csv", mass=None))
    data = json.loads(json.dumps(data))
    _validator("result.schema.json").validate(data)


def test_schema_rejects_a_bad_layout() -> None:
    bad = {"units": {"length": "furlong", "mass": "lb"}, "sensors": []}
    assert list(_validator("layout.schema.json").iter_errors(bad))
