"""The plan of a `flexmech sweep` from its options: the options checked, the swept field, the
path (the document's sweep section, or --path from --start to --stop or --until), the outputs
of the table and the figure."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from flexmech.api.cli.common import (
    OptionError,
    check_plot_option,
    default_xy,
    displacement_xy,
    number,
    output_hint,
    reaction_along,
)
from flexmech.api.cli.options import RESTARTS, choice, newton_options
from flexmech.models import COMPARED_MODELS, Mechanism, MechanismError
from flexmech.models.documents.sweep_spec import SweepSpec, SweepUntil
from flexmech.models.units import quantity_to_si
from flexmech.service.drawings.plotting import output_unit
from flexmech.service.solvers.newton import NewtonOptions


@dataclass(frozen=True)
class SweepPlan:
    """What every curve of one sweep command shares."""

    spec: SweepSpec
    unit: str  # of the swept field
    goal: str | None  # "OUTPUT = VALUE" where the path ends, when it ends at an output value
    x_output: str
    y_output: str
    restart: str
    stiffness: bool  # the field is a prescribed displacement and y_output the reaction along it


# --- the options -----------------------------------------------------------------------------
def check_path_options(
    path: str | None, start: str | None, stop: str | None, steps: int | None, until: str | None
) -> None:
    """--start, --stop, --steps and --until go with --path; --path needs --start and one end."""
    if path is None:
        given = [
            name
            for name, v in (("--start", start), ("--stop", stop), ("--steps", steps), ("--until", until))
            if v is not None
        ]
        if given:
            raise OptionError(given[0], "needs --path (without --path the document's sweep section is run)")
        return
    if start is None:
        raise OptionError("--start", "required with --path")
    if (stop is None) == (until is None):
        raise OptionError("--stop", "give exactly one of --stop and --until with --path")
    if steps is not None and steps < 1:
        raise OptionError("--steps", f"must be at least 1, got {steps}")


def given_value(text: str) -> float | str:
    """A command-line value: a number (document units), else a quantity string."""
    try:
        return float(text)
    except ValueError:
        return text


def field_value(mech: Mechanism, pointer: str, text: str, option: str) -> float:
    """A value of numeric field `pointer` given on the command line, in document units."""
    kind = mech.parameter_kind(pointer)
    return quantity_to_si(given_value(text), kind, mech.doc_unit(kind), option) / mech.doc_factor(kind)


def output_value(mech: Mechanism, name: str, text: str, option: str) -> float:
    """A value of output `name` given on the command line, in document units."""
    try:
        unit = output_unit(mech, name)
    except KeyError:
        raise OptionError(option, f"unknown output '{name}' ({output_hint(mech)})") from None
    kind = mech.graphs.output_kinds[mech.graphs.output_names.index(name)]
    return quantity_to_si(given_value(text), kind, unit, option) / mech.doc_factor(kind)


def swept_field(mech: Mechanism, path: str | None) -> str:
    """--path, else the path of the document's sweep section; checked to be a numeric field."""
    if path is None and mech.document.sweep is None:
        raise MechanismError("/sweep", "the document declares no sweep: give --path, --start and --stop or --until")
    swept = path if path is not None else mech.document.sweep.path
    mech.parameter_index(swept)
    return swept


def axes(mech: Mechanism, swept: str, x_output: str | None, y_output: str | None) -> tuple[str, str]:
    """The outputs of the table and the figure: as given, else for a prescribed displacement
    the moved body's displacement and the reaction along it (displacement_xy), else the first
    point output's x and y (default_xy)."""
    default_x, default_y = displacement_xy(mech, swept) or default_xy(mech)
    x_output, y_output = x_output or default_x, y_output or default_y
    for option, name in (("--x-output", x_output), ("--y-output", y_output)):
        if name not in mech.graphs.output_names:
            raise OptionError(option, f"unknown output '{name}' ({output_hint(mech)})")
    return x_output, y_output


def path_spec(
    mech: Mechanism, path: str, start: str, stop: str | None, steps: int | None, until: str | None
) -> SweepSpec:
    """The sweep of --path from --start to --stop, or until OUTPUT=VALUE, in --steps steps."""
    target = None
    if until is not None:
        name, sep, text = until.partition("=")
        if not sep or not name.strip() or not text.strip():
            raise OptionError("--until", f"expected OUTPUT=VALUE, got '{until}'")
        target = SweepUntil(output=name.strip(), equals=output_value(mech, name.strip(), text.strip(), "--until"))
    first = field_value(mech, path, start, "--start")
    last = field_value(mech, path, stop, "--stop") if stop is not None else None
    return SweepSpec(path=path, start=first, stop=last, steps=100 if steps is None else steps, until=target)


def goal_text(mech: Mechanism, spec: SweepSpec) -> str | None:
    if spec.until is None:
        return None
    equals = spec.until.equals
    if isinstance(equals, (int, float)):
        equals = number(equals, output_unit(mech, spec.until.output))
    return f"{spec.until.output} = {equals}"


def checked_options(
    plot: Path | None,
    restart: str,
    compare_models: bool,
    model: str | None,
    path: str | None,
    start: str | None,
    stop: str | None,
    steps: int | None,
    until: str | None,
    jacobian: str,
    line_search: bool,
    max_iterations: int,
) -> tuple[NewtonOptions, list[str | None]]:
    """The options checked before any document is read: Newton's options and the models swept."""
    check_plot_option(plot)
    choice("--restart", restart, RESTARTS)
    if compare_models and model is not None:
        raise OptionError("--compare-models", "runs every model; leave out --model")
    check_path_options(path, start, stop, steps, until)
    options = newton_options(jacobian, line_search, max_iterations)
    models = list(COMPARED_MODELS) if compare_models else [model]
    return options, models


def plan_sweep(
    first: Mechanism,
    path: str | None,
    start: str | None,
    stop: str | None,
    steps: int | None,
    until: str | None,
    x_output: str | None,
    y_output: str | None,
    restart: str,
) -> tuple[str, SweepPlan]:
    """The swept field and the plan of every curve, from the first model's mechanism."""
    swept = swept_field(first, path)
    x_output, y_output = axes(first, swept, x_output, y_output)
    spec = first.document.sweep if path is None else path_spec(first, swept, start, stop, steps, until)
    plan = SweepPlan(
        spec,
        first.doc_unit(first.parameter_kind(swept)),
        goal_text(first, spec),
        x_output,
        y_output,
        restart,
        y_output in reaction_along(first, swept),
    )
    return swept, plan
