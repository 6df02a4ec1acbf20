"""Shared fixtures: the seed-000 gripper in its example documents."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from models import compile_mechanism, load_document

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
ACTUATION = "/loads/actuation/force/1"


@pytest.fixture(scope="session")
def examples_dir() -> Path:
    return EXAMPLES


@pytest.fixture(scope="session")
def gripper_dict() -> dict:
    return json.loads((EXAMPLES / "gripper.json").read_text())


@pytest.fixture(scope="session", params=["linear", "partial_nonlinear"])
def gripper(request):
    """The silicon gripper, once per model."""
    return compile_mechanism(load_document(EXAMPLES / "gripper.json"), model=request.param)


@pytest.fixture(scope="session")
def gripper_pnl():
    return compile_mechanism(load_document(EXAMPLES / "gripper.json"), model="partial_nonlinear")
