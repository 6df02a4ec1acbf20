"""The client's method per analysis, made from the server's registry (GET /v1/analyses): a
method named after the analysis whose keyword arguments are its options and whose docstring
is its summary and its fields' descriptions. `client.analyze.equilibrium(example="gripper",
stiffness=True)` posts what `client.solve(example="gripper", analysis="equilibrium", stiffness=True)`
does, and answers an AnalysisReport (any analysis' report, its fields as attributes);
`help(client.analyze)` and `dir(client.analyze)` list what this server offers, a plugin's
analyses included. Pydantic and httpx only, like the rest of the client."""

from __future__ import annotations

import inspect
from collections.abc import Callable
from typing import Any

Schema = dict[str, Any]  # a JSON schema, or an analysis as GET /v1/analyses lists it

# The fields of every request (the mechanism and how to solve it), before the analysis' own.
COMMON = ("document", "example", "model", "overrides", "options")


def _type_of(schema: Schema) -> str:
    options = schema.get("anyOf")
    if options:
        return " | ".join(_type_of(s) for s in options)
    if "$ref" in schema:
        return str(schema["$ref"]).rsplit("/", 1)[-1]
    if "enum" in schema:
        return " | ".join(repr(v) for v in schema["enum"])
    return str(schema.get("type", "any"))


def docstring(
    analysis: Schema,
    returns: str = "the report (an AnalysisReport: its fields are attributes); non-convergence is its status",
) -> str:
    """The analysis' summary, then one line per option: name (type, default): description."""
    lines = [
        f"{analysis['summary']}.",
        "",
        "Common fields: document or example, model, overrides, options (Newton).",
        "",
        "Options:" if analysis["options"].get("properties") else "No options of its own.",
    ]
    required = set(analysis["options"].get("required", ()))
    for name, field in analysis["options"].get("properties", {}).items():
        default = "required" if name in required else f"default {field.get('default')!r}"
        unit = f" [{field['unit']}]" if field.get("unit") else ""
        lines.append(f"    {name} ({_type_of(field)}, {default}){unit}: {field.get('description', '')}")
    lines += ["", f"Returns {returns}."]
    return "\n".join(lines)


def _signature(analysis: Schema) -> inspect.Signature:
    keyword = inspect.Parameter.KEYWORD_ONLY
    parameters = [inspect.Parameter(name, keyword, default=None) for name in COMMON]
    required = set(analysis["options"].get("required", ()))
    for name, field in analysis["options"].get("properties", {}).items():
        default = inspect.Parameter.empty if name in required else field.get("default")
        parameters.append(inspect.Parameter(name, keyword, default=default))
    return inspect.Signature(parameters)


def method_of(analysis: Schema, solve: Callable[..., Any], returns: str | None = None) -> Callable[..., Any]:
    """A function calling `solve` with the analysis (or job kind) named, documented by its schema."""
    name = analysis["name"]

    def run(**fields: Any) -> Any:
        return solve(name, **{k: v for k, v in fields.items() if v is not None})

    run.__name__ = run.__qualname__ = name
    run.__doc__ = docstring(analysis, returns) if returns else docstring(analysis)
    run.__signature__ = _signature(analysis)  # type: ignore[attr-defined]
    return run


class Analyses:
    """The server's analyses (or job kinds) as methods, read once, when first asked: each calls
    `call(name, **fields)`."""

    def __init__(
        self,
        listing: Callable[[], list[Schema]],
        call: Callable[..., Any],
        what: str = "analysis",
        returns: str | None = None,
    ):
        self._listing = listing
        self._call = call
        self._what = what
        self._returns = returns
        self._methods: dict[str, Callable[..., Any]] | None = None

    def _all(self) -> dict[str, Callable[..., Any]]:
        if self._methods is None:
            self._methods = {a["name"]: method_of(a, self._call, self._returns) for a in self._listing()}
            self.__doc__ = f"The {self._what} methods of this server:\n\n" + "\n\n".join(
                f"{name}(...)\n{method.__doc__}" for name, method in self._methods.items()
            )
        return self._methods

    def __getattr__(self, name: str) -> Callable[..., Any]:
        if name.startswith("_"):
            raise AttributeError(name)
        methods = self._all()
        if name not in methods:
            raise AttributeError(f"the server has no {self._what} '{name}' (choices: {', '.join(methods)})")
        return methods[name]

    def __dir__(self) -> list[str]:
        return list(self._all())
