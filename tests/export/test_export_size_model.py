"""An export's C and its build are predicted from the mechanism before any code is generated
(issue 54, service.export.size_model): the predicted size against the C written, the issue's
largest link refused with its predicted size, the grippers accepted. Nothing is compiled here
(python3 -m benchmarks.export_size measured the builds the model is fitted to)."""

from __future__ import annotations

import json
import time

import pytest
from conftest import EXAMPLES

from flexmech.models import MechanismError, compile_mechanism, load_document
from flexmech.models.documents.document import MechanismDocument
from flexmech.service.costs import (
    EXPORT_BUILD_MEGABYTES,
    EXPORT_BUILD_SECONDS,
    Limits,
    check_document_cost,
    check_export_build,
    check_export_unknowns,
)
from flexmech.service.export.library import export_library
from flexmech.service.export.plan import ExportOptions
from flexmech.service.export.size_model import predicted_size

STRAINS = {"shear": True, "axial": True}
LINKS_ERROR = 0.10  # the model's C bytes on the links measured (size_model: -10%..+8%)
ISSUE_C_BYTES = 11_712_409  # the issue's link as written (benchmarks/export_size.py; the issue's 11.7 MB)


def cantilever(intervals: int, **fields) -> MechanismDocument:
    """examples/cantilever.json with its beam's discretization (its section given an area and its
    material a Poisson's ratio, for shear and axial strain)."""
    doc = json.loads((EXAMPLES / "cantilever.json").read_text())
    doc["sections"]["thesis"]["A"] = 20.0
    doc["materials"]["steel"]["nu"] = 0.3
    doc["elements"]["beam"].update(fields, intervals=intervals)
    return MechanismDocument.model_validate(doc)


CASES = {
    "gripper_exact": lambda: load_document(EXAMPLES / "gripper_exact.json"),
    "a link of 16 intervals at order 12": lambda: cantilever(16, order=12),
    "a link of 4 elements of degree 6 with strains": lambda: cantilever(
        4, discretization="elements", degree=6, **STRAINS
    ),
}


@pytest.mark.parametrize("case", CASES)
def test_the_predicted_c_size_is_the_written_one_within_the_models_error(case, tmp_path):
    mech = compile_mechanism(CASES[case](), None)
    predicted = predicted_size(mech.structure)
    export_library(mech, tmp_path / "x", "as in the document", ExportOptions(name="x"))
    written = sum(p.stat().st_size for p in (tmp_path / "x").iterdir() if p.suffix in (".c", ".h"))
    print(f"\n{case}: predicted {predicted.c_bytes:,} bytes of C, written {written:,}")
    assert abs(predicted.c_bytes / written - 1) <= LINKS_ERROR


def test_the_issues_largest_link_is_refused_saying_its_predicted_size():
    document = cantilever(56, order=12, **STRAINS)  # 56 x 12^2 = 8064 units of graph work, of 8192
    check_document_cost(document, None, Limits())  # the document's limits take it
    mech = compile_mechanism(document, None)
    check_export_unknowns(mech.n_free, Limits())  # 227 unknowns, of 400
    started = time.perf_counter()
    size = predicted_size(mech.structure)
    assert time.perf_counter() - started < 0.05  # before any code is generated, nothing built
    assert abs(size.c_bytes / ISSUE_C_BYTES - 1) <= LINKS_ERROR
    with pytest.raises(MechanismError) as refused:
        check_export_build(mech)
    message = refused.value.problem
    print(f"\n{refused.value.pointer}: {message}")
    assert refused.value.pointer == "/document/elements"
    assert f"writes about {size.c_bytes / 1e6:.1f} MB of C" in message and "11.4 MB" in message
    assert "with the rows of element 'beam' in one function of about 434,650 instructions" in message
    assert "needs about 82 s and" in message  # measured: 81.5 s, 2.2 GB
    assert f"the limit is {EXPORT_BUILD_SECONDS:.0f} s and {EXPORT_BUILD_MEGABYTES:.0f} MB as predicted" in message


@pytest.mark.parametrize("example", ["gripper", "gripper_exact"])
def test_the_grippers_are_accepted(example):
    mech = compile_mechanism(load_document(EXAMPLES / f"{example}.json"), None)
    check_export_unknowns(mech.n_free, Limits())
    check_export_build(mech)
    size = predicted_size(mech.structure)
    assert size.gcc_seconds < EXPORT_BUILD_SECONDS / 4  # measured: 0.8 s and 9.9 s


def test_a_link_at_order_12_is_taken_up_to_17_intervals():
    """The limit in a link's terms: 16 intervals at order 12 built in 29-34 s and 721 MB, 24 in
    78 s and 1.3 GB; 17 are predicted at 43 s and 791 MB, 18 at 48 s."""
    check_export_build(compile_mechanism(cantilever(17, order=12), None))
    with pytest.raises(MechanismError) as refused:
        check_export_build(compile_mechanism(cantilever(18, order=12), None))
    assert "one function of about 69,725 instructions: gcc -O2 needs about 48 s and 858 MB" in refused.value.problem
