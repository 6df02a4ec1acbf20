"""Contact in design optimization: an objective and a constraint naming contact results
(Example I at x_o = 64 mm: the least insertion force whose normal force is still 4 N, over the
finger's thickness). The optimum is where the constraint binds, which a bisection of plain
contact analyses finds independently."""

from __future__ import annotations

from mechanisms import example_one

from flexmech.models import compile_mechanism, load_document
from flexmech.models.documents.document import parse_optimize_spec
from flexmech.service.analyses.base import AnalysisRequest
from flexmech.service.analyses.contact import CONTACT
from flexmech.service.design.optimize import optimize
from flexmech.service.design.problem import design_problem


def normal_force(thickness: float) -> tuple[float, float]:
    doc = example_one(64.0)
    doc["sections"]["strip"]["h"] = thickness
    pair = CONTACT.run(compile_mechanism(load_document(doc)), AnalysisRequest())["pairs"]["insertion"]
    return pair["normal_force"], pair["force"][0]


def test_the_least_insertion_force_with_a_normal_force_bound():
    spec = parse_optimize_spec(
        {
            "design": [{"path": "/sections/strip/h", "lower": 2.0, "upper": 4.0}],
            "objective": {"output": "contacts.insertion.force_x", "sense": "maximize"},  # force_x < 0: the least push
            "constraints": [{"output": "contacts.insertion.normal_force", "lower": 4.0}],
        }
    )
    result = optimize(design_problem(compile_mechanism(load_document(example_one(64.0))), spec)).summary()
    assert result["status"] == "optimal", result["message"]
    found = result["design"]["/sections/strip/h"]
    low, high = 2.0, 4.0  # the normal force grows with the thickness: bisect for 4 N
    for _ in range(40):
        middle = (low + high) / 2
        low, high = (middle, high) if normal_force(middle)[0] < 4.0 else (low, middle)
    assert abs(found - (low + high) / 2) < 1e-6 * found
    assert abs(result["constraints"][0]["value"] - 4.0) < 1e-6 and result["constraints"][0]["active"]
    assert abs(result["objective"] - normal_force(found)[1]) < 1e-9 * abs(result["objective"])
