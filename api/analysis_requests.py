"""The request body of POST /v1/solve, made from the analyses registry: per analysis a model of
the request's common fields (the document, model, overrides, Newton options) and that
analysis' options, tagged by `analysis` (equilibrium when absent). OpenAPI shows the union with
its discriminator, so each analysis' fields are documented where they apply and a field that
belongs to another analysis is refused by name.

Built when the app is (api.app.create_app): analyses registered before then are served."""

from __future__ import annotations

from typing import Annotated, Any, Literal, Union

from pydantic import ConfigDict, Discriminator, Field, Tag

from flexmech.api.schemas import DocumentRequest
from flexmech.service.analyses import ANALYSES, Analysis, AnalysisOptions

DEFAULT_ANALYSIS = "equilibrium"

# Requests worth showing per analysis (schemathesis sends every example); the equilibrium's
# include values that once broke the service, answered 422 now.
_BAD_LENGTHS = ("10**10**10 mm", "5 percent", "mm", "1e308 mm", "5e-324", "1" * 90 + " mm")
_BAD_EXPRESSIONS = ("9**9**9", "1/0", "(-1)**0.5", "log(0)", "exp(1000)*0", "sqrt(-1)")


def _rod(expression: str) -> dict:
    return {
        "units": {"length": "m", "force": "N", "stress": "Pa", "angle": "rad"},
        "materials": {"m": {"E": 2e11}},
        "sections": {"s": {"b": 0.01, "h": 0.001}},
        "bodies": {"wall": {"fixed": True, "position": [0, 0]}, "tip": {"position": [0.1, 0]}},
        "elements": {
            "L": {
                "type": "link",
                "from": "wall",
                "to": "tip",
                "length": 0.1,
                "material": "m",
                "section": "s",
                "shape": {"type": "expression", "expression": expression},
            }
        },
    }


EXAMPLES: dict[str, list[dict[str, Any]]] = {
    "equilibrium": [
        {"example": "gripper", "overrides": {"/loads/actuation/force/1": 50}},
        {"example": "gripper", "target": {"path": "/loads/actuation/force/1", "output": "end_effector.x", "equals": 0}},
        *({"example": "gripper", "overrides": {"/elements/a/radius": value}} for value in _BAD_LENGTHS),
        *({"document": _rod(text)} for text in _BAD_EXPRESSIONS),
    ],
    "linearization": [{"example": "gripper", "analysis": "linearization", "at": "undeformed"}],
    "inverse": [{"example": "gripper", "analysis": "inverse", "displacements": {"input": [1e308, 0, 0]}}],
}


def _tag(value: Any) -> str | None:
    name = value.get("analysis", DEFAULT_ANALYSIS) if isinstance(value, dict) else getattr(value, "analysis", None)
    return f"[{name}]" if isinstance(name, str) else None


def _camel(name: str) -> str:
    return "".join(part.capitalize() for part in name.split("_"))


def request_model(analysis: Analysis) -> type[DocumentRequest]:
    """The request of one analysis: the common fields, `analysis` (a literal: the union's tag)
    and its options."""
    examples = EXAMPLES.get(analysis.name, [{"example": "gripper", "analysis": analysis.name}])
    namespace = {
        "__module__": __name__,
        "__doc__": f"The {analysis.name} analysis: {analysis.summary}.",
        "__annotations__": {"analysis": Literal[analysis.name]},
        "analysis": Field(analysis.name if analysis.name == DEFAULT_ANALYSIS else ..., description="the analysis"),
        "model_config": ConfigDict(extra="forbid", allow_inf_nan=False, json_schema_extra={"examples": examples}),
    }
    return type(f"{_camel(analysis.name)}Solve", (DocumentRequest, analysis.Options), namespace)


def solve_request_type() -> Any:
    """The body of /v1/solve: the union over the registered analyses, tagged by `analysis`."""
    members = tuple(Annotated[request_model(a), Tag(f"[{a.name}]")] for a in ANALYSES)
    return Annotated[Union[members], Discriminator(_tag)]  # noqa: UP007 (a union built at run time)


def options_of(analysis: Analysis, request: DocumentRequest) -> AnalysisOptions:
    """The analysis' typed options out of its request (already checked: no validation again)."""
    return analysis.Options.model_construct(**{name: getattr(request, name) for name in analysis.Options.model_fields})


def documented(schema: dict) -> dict:
    """The OpenAPI document with /v1/solve's body (and the analysis job's) named SolveRequest and its discriminator
    mapped (pydantic leaves a run-time tag without one), and each analysis' result model among
    the 200 answers' schemas."""
    post = schema.get("paths", {}).get("/v1/solve", {}).get("post")
    if post is None:
        return schema
    components = schema.setdefault("components", {}).setdefault("schemas", {})
    body = post["requestBody"]["content"]["application/json"]["schema"]
    mapping = {a.name: f"#/components/schemas/{_camel(a.name)}Solve" for a in ANALYSES}
    components["SolveRequest"] = {
        **body,
        "title": "SolveRequest",
        "discriminator": {"propertyName": "analysis", "mapping": mapping},
    }
    for path in ("/v1/solve", "/v1/analysis-jobs"):  # the analysis job takes the same body
        taking = schema["paths"].get(path, {}).get("post")
        if taking is not None:
            taking["requestBody"]["content"]["application/json"]["schema"] = {
                "$ref": "#/components/schemas/SolveRequest"
            }
    results = {}
    for a in ANALYSES:
        result = a.Result.model_json_schema(ref_template="#/components/schemas/{model}")
        components.update(result.pop("$defs", {}))
        name = f"{_camel(a.name)}Result"
        components[name] = {**result, "title": name}
        results[a.name] = f"#/components/schemas/{name}"
    answer = post["responses"]["200"]["content"]["application/json"]
    answer["schema"] = {
        "anyOf": [answer["schema"], *({"$ref": ref} for ref in results.values())],
        "description": "the report of the analysis asked for (SolveResponse holds every field any "
        "analysis reports; each analysis' Result model says what it reports)",
    }
    return schema
