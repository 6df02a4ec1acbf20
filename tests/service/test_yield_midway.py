"""Work that cannot be kept in part gives its worker up at once when asked to yield (issue 53):
an optimization's start and an impact study's run end mid-way, are not stored, and are left to
run again, whole (service.jobs.control.TaskControl.stop_or_yield). In-process: the runner's
yield signal is a file, made here by a timer while the task runs."""

from __future__ import annotations

import json
import threading
import time

import pytest
from conftest import EXAMPLES

from flexmech.service.jobs.base import task_remainder
from flexmech.service.jobs.impact_study import IMPACT_STUDY
from flexmech.service.jobs.optimize import OPTIMIZE

ASKED_AFTER = 1.0  # seconds into the task when the yield is asked


def _example(name: str) -> dict:
    return json.loads((EXAMPLES / f"{name}.json").read_text())


def _long_start() -> dict:
    """gripper_sections' design problem; its start 2 runs IPOPT for its 100000 iterations (about
    80 s here) without converging."""
    document = _example("gripper_sections")
    return {"document": document, "problem": {**document["optimize"], "starts": 3, "max_iterations": 100_000}}


def _long_run() -> dict:
    """csfh's nominal run for 20 s in steps of at most 1e-5 s: about 3 s of stepping here."""
    return {
        "document": _example("csfh"),
        "simulate": {"until": 20, "max_step": 1e-5},
        "study": {"fields": [{"path": "/bodies/hinge/mass", "step": 0.001}]},
    }


CASES = {"optimize": (OPTIMIZE, _long_start, [2]), "impact_study": (IMPACT_STUDY, _long_run, [0])}


@pytest.mark.parametrize("case", list(CASES))
def test_a_point_asked_to_yield_mid_way_ends_unstored_and_is_left_to_run_again(case, tmp_path):
    kind, spec_of, indices = CASES[case]
    spec, signal = spec_of(), tmp_path / "yield"
    task = {"indices": indices, "control": {"file": str(tmp_path / "cancelled"), "yield_file": str(signal)}}
    if case == "impact_study":
        task["max_steps"] = 2_000_000
    timer = threading.Timer(ASKED_AFTER, signal.touch)
    started = time.perf_counter()
    timer.start()
    try:
        points = kind.run(spec, task)
    finally:
        timer.cancel()
    print(f"\n{case}: the point gave its worker up {time.perf_counter() - started - ASKED_AFTER:.2f} s after the ask")
    assert signal.exists(), "the point ended before it was asked to yield: make it longer"
    assert points == []  # the point cut short is not stored
    assert task_remainder(kind, task, {})["indices"] == indices  # it runs again, whole
