"""The mechanism document: a validated description of a planar compliant mechanism.

Named collections (materials, sections, bodies, elements, loads, outputs) are JSON objects
keyed by name, so every field has a stable JSON pointer such as /sections/flex/h or
/loads/actuation/force/1. Numbers are plain (in the document's declared units) or strings
with units ("25 um"). Cross references and physical ranges are checked when the document is
compiled (models.graph.mechanism), where each error names its field.
"""

from __future__ import annotations

import difflib
import json
from functools import lru_cache
from pathlib import Path
from typing import Annotated, Any, Literal, Union

from pydantic import Field, ValidationError, field_validator, model_validator

from flexmech.models.contact.schema import OBJECT_TYPES, SITE_TYPES, Contacts
from flexmech.models.documents.fields import (
    MAX_QUANTITY_CHARS,
    Description,
    Name,
    Number,
    Pointer,
    StrictModel,
    UnitName,
    Vec2,
)
from flexmech.models.documents.optimize_spec import OptimizeSpec
from flexmech.models.documents.reading import parse_json, parse_yaml
from flexmech.models.documents.sections import Section
from flexmech.models.documents.simulation_spec import SimulateSpec
from flexmech.models.documents.sweep_spec import SweepSpec
from flexmech.models.documents.text_bounds import too_long
from flexmech.models.documents.tolerances import TolerancesSpec
from flexmech.models.elements import FAMILIES
from flexmech.models.elements.link_schema import SHAPE_TYPES
from flexmech.models.errors import MechanismError, pointer_of
from flexmech.models.units import quantity_to_si


class Units(StrictModel):
    """Units of the bare numbers in the document; results come back in the same units."""

    length: UnitName = "m"
    force: UnitName = "N"
    stress: UnitName = "Pa"
    angle: UnitName = "deg"
    mass: UnitName = "kg"


class Material(StrictModel):
    E: Number = Field(description="Young's modulus")
    nu: Number | None = Field(default=None, description="Poisson's ratio")
    G: Number | None = Field(default=None, description="shear modulus (default E / (2 (1 + nu)))")
    density: Number | None = Field(
        default=None, description="mass per volume: links made of it have mass (and weight under gravity)"
    )
    stress_limit: Number | None = Field(
        default=None,
        description="allowable stress (document stress units, positive): the drawing marks it on its "
        "stress scale and flags the parts of a flexure or link above it; no analysis enforces it",
    )

    @field_validator("stress_limit")
    @classmethod
    def _positive_stress(cls, value: float | str | None) -> float | str | None:
        """A stress (a bare number, or a quantity with a unit of stress) above zero; its
        magnitude in the document's unit is checked where it is used (service.drawings.stresses)."""
        if value is None:
            return None
        try:
            si = quantity_to_si(value, "stress", "Pa", "/stress_limit")
        except MechanismError as exc:
            raise ValueError(exc.problem) from None
        if si <= 0:
            raise ValueError(
                f"must be positive, got {value:g}" if isinstance(value, float) else f"must be positive, got {value}"
            )
        return value


class Body(StrictModel):
    fixed: bool = False
    joint: bool = Field(
        default=False,
        description="a zero-size joint of a link network (Lan 2005): "
        "if every link attached to it is pinned, it has no rotation",
    )
    position: Vec2 = Field(description="reference point (e.g. mass centre), undeformed, global frame")
    angle: Number = 0.0
    mass: Number | None = Field(
        default=None,
        description="in the document's mass unit: the mass matrix, and a weight at the mass centre under gravity",
    )
    inertia: Number | None = Field(default=None, description="about the reference point")
    center_of_mass: Vec2 | None = Field(
        default=None, description="from the reference point, body axes (default: the reference point)"
    )


def _element_union() -> Any:
    """A document element: the section of one registered family, told apart by its `type`."""
    schemas = FAMILIES.schemas()
    union = Union[schemas]  # noqa: UP007 (a union of a tuple: the registered families' schemas)
    return Annotated[union, Field(discriminator="type")] if len(schemas) > 1 else schemas[0]


Element = _element_union()


class _PointOnBody(StrictModel):
    body: Name
    at: Vec2 | None = Field(default=None, description="global point, undeformed configuration")
    offset: Vec2 | None = Field(default=None, description="from the body reference point, body axes")

    @model_validator(mode="after")
    def _one_location(self):
        if self.at is not None and self.offset is not None:
            raise ValueError("give either 'at' or 'offset', not both")
        return self


class ForceLoad(_PointOnBody):
    """A force of fixed global direction at a point of a body (default: its reference point)."""

    type: Literal["force"]
    force: Vec2


class MomentLoad(StrictModel):
    type: Literal["moment"]
    body: Name
    moment: Number


class PrescribedDisplacement(StrictModel):
    """Prescribed motion of a body's reference point; a component left out stays free."""

    type: Literal["displacement"]
    body: Name
    dx: Number | None = None
    dy: Number | None = None
    rotation: Number | None = None

    @model_validator(mode="after")
    def _something_prescribed(self):
        if self.dx is None and self.dy is None and self.rotation is None:
            raise ValueError("prescribe at least one of dx, dy, rotation")
        return self


Load = Annotated[ForceLoad | MomentLoad | PrescribedDisplacement, Field(discriminator="type")]


class PointOutput(_PointOnBody):
    type: Literal["point"]


class ReactionOutput(StrictModel):
    type: Literal["reaction"]
    body: Name


Output = Annotated[PointOutput | ReactionOutput, Field(discriminator="type")]


class InverseSpec(StrictModel):
    """Data of the link inverse (Lan 2005 Sec. 5.3): the deformed angle psi(u) of every link
    ({"polynomial": [c0, ...]} or {"samples": [...], "u": [...]}, radians), internal forces
    ({link: {"h": value, "v": value}}) and the load components they determine."""

    shapes: dict[Name, Any]
    internal_forces: dict[Name, Any] = {}
    unknown_loads: list[Pointer] = []


class MechanismDocument(StrictModel):
    schema_version: Literal[1] = 1
    name: Name = "mechanism"
    description: Description = ""
    units: Units = Units()
    materials: dict[Name, Material] = {}
    sections: dict[Name, Section] = {}
    bodies: dict[Name, Body]
    gravity: Vec2 | None = Field(
        default=None,
        description="acceleration of gravity (length unit / s^2): body masses and links with a density weigh",
    )
    elements: dict[Name, Element] = {}
    loads: dict[Name, Load] = {}
    outputs: dict[Name, Output] = {}
    contacts: Contacts | None = Field(
        default=None, description="rigid objects, contact sites and pairs (the contact analysis)"
    )
    impacts: Any = Field(default=None, description="replaced by `contacts`: `flexmech upgrade DOC` converts it")
    sweep: SweepSpec | None = None
    inverse: InverseSpec | None = None
    optimize: OptimizeSpec | None = None
    simulate: SimulateSpec | None = Field(default=None, description="a time simulation (the simulate analysis)")
    tolerances: TolerancesSpec | None = Field(
        default=None, description="how the made part scatters, and the specs it must meet (the tolerance analysis)"
    )

    @field_validator("impacts")
    @classmethod
    def _upgraded(cls, impacts: Any) -> None:
        if impacts is not None:
            raise ValueError(UPGRADE_HINT)
        return None

    def to_json_dict(self) -> dict[str, Any]:
        return self.model_dump(mode="json", by_alias=True, exclude_none=True)


def _families_changed() -> None:
    """A family registered (or removed) after import: the document's elements take its
    section (pydantic builds the validator again from the new union)."""
    MechanismDocument.model_fields["elements"].annotation = dict[Name, _element_union()]
    MechanismDocument.model_rebuild(force=True)
    _field_names.cache_clear()


FAMILIES.on_change(_families_changed)

UPGRADE_HINT = (
    "the `impacts` section is now part of `contacts` (its surfaces are sites and objects, its pairs "
    "contact pairs with their laws): convert the document with `flexmech upgrade DOC` (or POST it to "
    "/v1/documents/upgrade)"
)

# pydantic's error types when a value is not a number (a Number is a float or a quantity string)
_NOT_A_NUMBER = {"float_type", "string_type", "float_parsing", "finite_number", "string_too_long", "bool_type"}


def _raise_first(exc: ValidationError) -> None:
    """Turn pydantic's error list into our error type, naming one offending field: an unknown
    field first (a typo explains the rest), and counting the other fields with problems; its
    `problems` list every field with its own message, that one first."""
    errors = exc.errors()
    first = next((e for e in errors if e["type"] == "extra_forbidden"), errors[0])
    location, message = _problem(first, errors)
    at_each: dict[tuple, dict] = {}
    for error in errors:
        at_each.setdefault(_field_location(error["loc"]), error)
    at_each.pop(_field_location(first["loc"]))
    rest = [_problem(error, errors) for error in at_each.values()]
    problems = (
        (pointer_of(location), message),
        *((pointer_of(where), what) for where, what in rest if where != location),
    )
    others = len({_field_location(e["loc"]) for e in errors} - {location, _field_location(first["loc"])})
    if others:
        message += f" (and {others} more field{'s' if others > 1 else ''} with problems)"
    raise MechanismError(pointer_of(location), message, problems) from None


def _problem(error: dict, errors: list[dict]) -> tuple[tuple, str]:
    """The field one of pydantic's errors names, and its problem in our words."""
    location = _field_location(error["loc"])
    here = [e for e in errors if _field_location(e["loc"]) == location]
    message = error["msg"].removeprefix("Value error, ")  # pydantic's prefix to our validators' words
    if error["type"] == "missing":
        message = "required field is missing"
    elif error["type"] == "extra_forbidden":
        message = unknown_field_message(str(location[-1]) if location else "")
    elif error["type"] in ("union_tag_invalid", "union_tag_not_found"):
        location, message = _tag_problem(error, location)
    elif all(e["type"] == "string_too_long" for e in here):  # a text (not a Number's quantity, also a float)
        key = error["loc"][-1] == "[key]"  # a key too long: the error is its object's, the key not echoed
        location = _field_location(error["loc"][:-2]) if key else location
        message = too_long(error["ctx"]["max_length"], len(error["input"]), key)
    elif all(e["type"] in _NOT_A_NUMBER for e in here):
        message = (
            f"expected a number (or a quantity string like '25 um', at most {MAX_QUANTITY_CHARS} "
            f"characters), got {_shown(error.get('input'))}"
        )
    return location, message


def _tag_problem(error: dict, location: tuple) -> tuple[tuple, str]:
    """An object of a tagged collection whose tag (`type`) is missing or unknown: the tag's
    location, and the kinds there are (the nearest first, if one is close)."""
    context = error.get("ctx", {})
    tag_field = str(context.get("discriminator", "'type'")).strip("'")
    if error["type"] == "union_tag_not_found":
        return (*location, tag_field), "required field is missing"
    kinds = [kind.strip().strip("'") for kind in str(context.get("expected_tags", "")).split(",") if kind.strip()]
    tag = str(context.get("tag", ""))
    close = difflib.get_close_matches(tag, kinds, n=1, cutoff=0.75)
    hint = f"did you mean '{close[0]}'? " if close else ""
    return (*location, tag_field), f"unknown {tag_field} '{tag}' ({hint}{tag_field}s: {', '.join(kinds)})"


def _shown(value: Any) -> str:
    text = json.dumps(value) if isinstance(value, (bool, int, float, str)) or value is None else type(value).__name__
    return text if len(text) <= 40 else text[:40] + "..."


@lru_cache(maxsize=1)
def _field_names() -> tuple[str, ...]:
    """Every field name (and alias) of the document's models, for suggestions."""
    names, seen, stack = set(), set(), [MechanismDocument]
    while stack:
        model = stack.pop()
        if model in seen:
            continue
        seen.add(model)
        for name, info in model.model_fields.items():
            names.add(info.alias or name)
            stack.extend(_models_in(info.annotation))
    return tuple(sorted(names))


def _models_in(annotation: Any) -> list[type]:
    """The document models an annotation holds (through unions, containers and Annotated)."""
    found, stack = [], [annotation]
    while stack:
        item = stack.pop()
        if isinstance(item, type) and issubclass(item, StrictModel):
            found.append(item)
        stack.extend(getattr(item, "__args__", ()) or ())
        if getattr(item, "__origin__", None) is not None and hasattr(item, "__metadata__"):
            stack.append(item.__origin__)  # Annotated[X, ...]
    return found


def unknown_field_message(key: str) -> str:
    """ "unknown field 'radious' (did you mean 'radius'?)"; a field that other kinds of object
    have (a rectangle section's 'A') is said to be theirs, not suggested as itself."""
    if key in _field_names():
        return f"unknown field '{key}' (other kinds of object have it, this one does not)"
    close = difflib.get_close_matches(key, _field_names(), n=1, cutoff=0.75)
    return f"unknown field '{key}'" + (f" (did you mean '{close[0]}'?)" if close else "")


_TAGGED_COLLECTIONS = {"elements", "loads", "outputs", "sections"}
_SHAPE_TAGS = set(SHAPE_TYPES)
_CONTACT_TAGS = set(OBJECT_TYPES) | set(SITE_TYPES)
_UNION_MEMBERS = {"float", "str", "int", "bool", "none", "constrained-str"}


def _field_location(loc: tuple) -> tuple:
    """pydantic's error location without the labels it adds for unions: the discriminator
    value after the key in a tagged collection (/loads/<name>/<tag>/...) and member type
    names such as 'float' or 'tuple[...]' of plain unions."""
    parts = list(loc)
    if len(parts) > 2 and parts[0] in _TAGGED_COLLECTIONS and isinstance(parts[2], str):
        del parts[2]
    if "shape" in parts[:-2] and parts[parts.index("shape") + 1] in _SHAPE_TAGS:
        del parts[parts.index("shape") + 1]
    if len(parts) > 3 and parts[0] == "contacts" and parts[1] in ("objects", "sites") and parts[3] in _CONTACT_TAGS:
        del parts[3]
    return tuple(p for p in parts if not (isinstance(p, str) and (p in _UNION_MEMBERS or "[" in p)))


def parse_document(data: dict[str, Any]) -> MechanismDocument:
    """Validate a document given as a dict (parsed JSON or YAML)."""
    if not isinstance(data, dict):
        raise MechanismError("", "a mechanism document must be a JSON object")
    try:
        return MechanismDocument.model_validate(data)
    except ValidationError as exc:
        _raise_first(exc)
        raise  # unreachable: _raise_first always raises


def parse_optimize_spec(data: Any) -> OptimizeSpec:
    """Validate a design problem given on its own (pointers relative to it)."""
    if not isinstance(data, dict):
        raise MechanismError("", "a design problem must be a JSON object")
    try:
        return OptimizeSpec.model_validate(data)
    except ValidationError as exc:
        _raise_first(exc)
        raise


def load_document(source: str | Path | dict[str, Any]) -> MechanismDocument:
    """Read and validate a mechanism document from a JSON/YAML file path or a dict."""
    if isinstance(source, dict):
        return parse_document(source)
    path = Path(source)
    try:
        text = path.read_bytes()
    except OSError as exc:
        raise MechanismError("", f"cannot read {path}: {exc.strerror}") from None
    if path.suffix.lower() in {".yaml", ".yml"}:
        return parse_document(parse_yaml(text, str(path)))
    return parse_document(parse_json(text, str(path)))
