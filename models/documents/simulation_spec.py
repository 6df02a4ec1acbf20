"""The document's `simulate` section: how a time simulation runs (models.graph.dynamics,
service.dynamics). Times are in seconds; history values in the document unit of the field
they drive."""

from __future__ import annotations

from typing import Any, Literal

from pydantic import Field, ValidationInfo, field_validator

from flexmech.models.documents.fields import Name, OutputName, Pointer, StrictModel


class BodyStart(StrictModel):
    """A free body's start (impact simulations): its mass centre's displacement from the drawn
    pose and rotation (document length and angle units), and its velocity (per second)."""

    displacement: tuple[float, float, float] = (0.0, 0.0, 0.0)
    velocity: tuple[float, float, float] = (0.0, 0.0, 0.0)


# More steps than any limit of the server or the command line, and few enough that a step
# count is an exact integer (until / step of 1e300 / 1e-300 would be infinite).
MAX_STEP_COUNT = 1e12
IMPACT_SCHEMES = ("event_driven", "moreau")  # rigid bodies with impacts (service.impacts)
DEFAULT_MAX_POINTS = 2000  # an impact report's states: about 0.6 MB of JSON for one body and pair


class SimulateSpec(StrictModel):
    until: float | None = Field(default=None, gt=0, allow_inf_nan=False, description="end time (s)")
    step: float = Field(default=1e-3, gt=0, allow_inf_nan=False, description="time step (s); adaptive: the first")
    adaptive: bool = Field(default=False, description="steps that follow the local error estimate")
    tolerance: float = Field(
        default=1e-6,
        gt=0,
        le=1e-1,
        description="adaptive and event_driven: a step's local "
        "error, relative to the mechanism's length scale (event_driven: the smallest clearance)",
    )
    max_step: float | None = Field(
        default=None,
        gt=0,
        allow_inf_nan=False,
        description="adaptive and event_driven: the longest step (s; event_driven's default: until / 500)",
    )
    scheme: Literal["generalized_alpha", "newmark", "sdirk4", "event_driven", "moreau"] = Field(
        default="generalized_alpha",
        description="generalized-alpha (second order, rho_inf), Newmark (a1, a2), or sdirk4 (fourth order, "
        "L-stable, five implicit stages a step: long steps where the motion is smooth); "
        "for rigid bodies with impacts: event_driven (adaptive Dormand-Prince with located contact events) or "
        "moreau (Moreau-Jean midpoint time stepping, `step`)",
    )
    accuracy: float | None = Field(
        default=None,
        gt=0,
        le=1e-1,
        allow_inf_nan=False,
        description="a target for the error of the named `outputs`, each relative to its largest excursion "
        "from its start value: from the document's own, the run refines its links' elements and its steps (the "
        "step, or the adaptive steps' tolerance) until the estimate (one refinement of each) is within it, and "
        "reports each output's estimate (link schemes)",
    )
    rho_inf: float = Field(
        default=0.95,
        ge=0,
        le=1,
        description="generalized-alpha: spectral radius at high frequency (1: no numerical dissipation)",
    )
    a1: float = Field(default=0.5, ge=0.5, le=1.5, description="Newmark gamma (Lan 2005 Eq. 3.15; 0.5 + sigma)")
    a2: float = Field(
        default=0.5,
        ge=0.5,
        le=3.0,
        description="Newmark 2 beta (Lan 2005 Eq. 3.15; (1 + sigma)^2 / 2); "
        "unconditionally stable for a2 >= a1; a conditionally stable pair is refused with its "
        "critical step",
    )
    damping: float = Field(
        default=0.0,
        ge=0,
        allow_inf_nan=False,
        description="mass-proportional damping coefficient alpha (1/s): forces -alpha M v",
    )
    start: Literal["rest", "equilibrium"] = Field(
        default="rest",
        description="rest: undeformed and still; equilibrium: the static state under the "
        "document's values, released at t = 0 into the histories",
    )
    histories: dict[Pointer, Any] = Field(
        default={},
        max_length=256,
        description="field pointer -> a number, an "
        "expression in t, {table: [[t, value], ...]} or {pieces: [{until, value}, ...]}",
    )
    initial: dict[Name, BodyStart] = Field(
        default={}, max_length=64, description="impact simulations: body name -> its start displacement and velocity"
    )
    flexure_stiffness: Literal["constant", "turning"] = Field(
        default="constant",
        description="curved beams in impact simulations: the closed-form stiffness of seed 000 "
        "constant in space (conservative, the default), or turning with the body (seed 004 Eq. 8, not conservative)",
    )
    sensitivities: list[Pointer] = Field(
        default=[],
        max_length=16,
        description="event_driven: numbers of the "
        "document (JSON pointers, e.g. /contacts/pairs/conjugate/normal/restitution) "
        "to differentiate the state at the end time by, exactly",
    )
    every: int = Field(default=1, ge=1, le=1_000_000, description="keep every n-th step")
    max_points: int = Field(
        default=DEFAULT_MAX_POINTS,
        ge=2,
        le=100_000,
        description="impact simulations (event_driven, moreau): "
        "the states the report keeps, spread evenly over the run (after `every`), and besides "
        "them the states around each contact's onset and end",
    )
    outputs: list[OutputName] | None = Field(
        default=None, max_length=512, description="outputs to record (default: all)"
    )
    shapes: bool = Field(
        default=False, description="also the links' deformed centre lines at every kept state (snapshots, animation)"
    )
    min_step: float = Field(
        default=1e-9,
        gt=0,
        allow_inf_nan=False,
        description="adaptive: the shortest step (s); a step that must be shorter ends the run with status min_step",
    )
    max_steps: int | None = Field(
        default=None,
        ge=1,
        description="the most time steps (adaptive: accepted steps, "
        "then the run ends with status step_limit); default and cap: the server's limit",
    )
    compiled: bool | None = Field(
        default=None,
        description="deprecated and ignored: the server compiles element "
        "kernels in its build queue and runs them compiled once built",
    )

    @field_validator("step")
    @classmethod
    def _countable(cls, step: float, info: ValidationInfo) -> float:
        until = info.data.get("until")
        if until is not None and not until / step <= MAX_STEP_COUNT:
            raise ValueError(f"{until:g} s in steps of {step:g} s would be more than {MAX_STEP_COUNT:g} steps")
        return step

    @field_validator("sensitivities")
    @classmethod
    def _of_event_driven(cls, pointers: list[str], info: ValidationInfo) -> list[str]:
        scheme = info.data.get("scheme")
        if pointers and scheme != "event_driven":
            raise ValueError(
                f"sensitivities are those of an event_driven run (its located contact events move with "
                f"the numbers); the {scheme} scheme has none: set scheme to event_driven"
            )
        return [pointer if pointer.startswith("/") else f"/{pointer}" for pointer in pointers]

    @field_validator("accuracy")
    @classmethod
    def _of_link_schemes(cls, accuracy: float | None, info: ValidationInfo) -> float | None:
        scheme = info.data.get("scheme")
        if accuracy is not None and scheme in IMPACT_SCHEMES:
            raise ValueError(
                f"an accuracy target picks the links' elements and steps; the {scheme} scheme of rigid bodies "
                "follows its own `tolerance`"
            )
        return accuracy

    @field_validator("max_points")
    @classmethod
    def _impacts_only(cls, max_points: int, info: ValidationInfo) -> int:
        """Only impact reports are thinned by it: another value for a link scheme is refused
        (the default passes, as sections are often copied whole from a dump)."""
        scheme = info.data.get("scheme")
        if scheme is not None and scheme not in IMPACT_SCHEMES and max_points != DEFAULT_MAX_POINTS:
            raise ValueError(
                f"max_points thins impact simulations ({', '.join(IMPACT_SCHEMES)}); the {scheme} "
                "scheme keeps every n-th step (`every`)"
            )
        return max_points


def critical_step_factor(gamma: float, beta: float) -> float:
    """Omega_crit = omega_max h_crit of a conditionally stable Newmark pair, undamped (Hughes
    2000, Eq. 9.1.36: (gamma / 2 - beta)^(-1/2))."""
    return (gamma / 2 - beta) ** -0.5
