"""A command for every registered analysis that has no command of its own (`flexmech
equilibrium DOC --stiffness`, `flexmech linearization DOC --at undeformed`, and any a plugin
registers): its flags are the fields of the analysis' options model, each with the field's
description (and unit) as its help; a field that is an object or a list takes JSON. The
options are checked by the model, a problem named by its flag. It prints the report's status,
its numbers and tables of its named numbers, and writes the report with --json, the same
report POST /v1/solve answers."""

from __future__ import annotations

import inspect
import json
import types
import typing
from collections.abc import Collection
from pathlib import Path
from typing import Annotated, Any, Literal

import typer
import typer.main
from pydantic import ValidationError
from rich.console import Console

from flexmech.api.cli.catalog import command_names
from flexmech.api.cli.common import (
    EXIT_NOT_CONVERGED,
    OptionError,
    consoles,
    number,
    shown,
    table_of,
    user_errors,
    write_json,
)
from flexmech.api.cli.options import (
    DocArg,
    JacobianOpt,
    JsonOpt,
    LineSearchOpt,
    MaxIterOpt,
    ModelOpt,
    SetOpt,
    mechanism,
    newton_options,
)
from flexmech.api.cli.record_tables import is_records, records_table
from flexmech.api.cli.report_tables import print_status
from flexmech.service.analyses import Analysis, AnalysisRequest
from flexmech.service.analyses.base import Analyses

FINE = ("converged", "finished")


def flag(name: str) -> str:
    return "--" + name.replace("_", "-")


def _plain(annotation: Any) -> Any:
    """The annotation without None (Optional)."""
    if typing.get_origin(annotation) in (typing.Union, types.UnionType):
        rest = [a for a in typing.get_args(annotation) if a is not type(None)]
        return rest[0] if len(rest) == 1 else annotation
    return annotation


def _help(info, choices: tuple | None) -> str:
    extra = info.json_schema_extra if isinstance(info.json_schema_extra, dict) else {}
    text = (info.description or "").rstrip(".")
    if extra.get("unit"):
        text += f" [{extra['unit']}]"
    if choices:
        text += f" ({' | '.join(map(str, choices))})"
    return text + "."


def option_parameter(name: str, info) -> inspect.Parameter:
    """The flag of one options field: a bool is --x/--no-x, a number or a word takes its value,
    a choice names its choices, anything else takes JSON."""
    kind = _plain(info.annotation)
    choices = typing.get_args(kind) if typing.get_origin(kind) is Literal else None
    if kind is bool:
        annotation = Annotated[
            bool | None,
            typer.Option(f"{flag(name)}/--no-{name.replace('_', '-')}", help=_help(info, None), show_default=False),
        ]
    elif kind in (int, float, str) or choices:
        python = str if choices else kind
        annotation = Annotated[python | None, typer.Option(flag(name), help=_help(info, choices), show_default=False)]
    else:
        annotation = Annotated[
            str | None, typer.Option(flag(name), metavar="JSON", help=_help(info, None), show_default=False)
        ]
    return inspect.Parameter(name, inspect.Parameter.KEYWORD_ONLY, default=None, annotation=annotation)


COMMON = [
    ("document", DocArg),
    ("model", ModelOpt),
    ("sets", SetOpt),
    ("jacobian", JacobianOpt),
    ("line_search", LineSearchOpt),
    ("max_iterations", MaxIterOpt),
    ("json_out", JsonOpt),
]
COMMON_DEFAULTS = {
    "model": None,
    "sets": None,
    "jacobian": "full",
    "line_search": True,
    "max_iterations": 50,
    "json_out": None,
}


def typed_options(analysis: Analysis, given: dict[str, Any]):
    """The options model from the flags given (JSON flags parsed); OptionError names the flag."""
    fields = {}
    for name, value in given.items():
        if value is None:
            continue
        kind = _plain(analysis.Options.model_fields[name].annotation)
        if isinstance(value, str) and kind not in (str, int, float, bool) and typing.get_origin(kind) is not Literal:
            try:
                value = json.loads(value)
            except json.JSONDecodeError as exc:
                raise OptionError(flag(name), f"not JSON: {exc.msg}") from None
        fields[name] = value
    try:
        return analysis.Options.model_validate(fields)
    except ValidationError as exc:
        first = exc.errors()[0]
        inner = "/".join(str(p) for p in first["loc"][1:])
        raise OptionError(flag(str(first["loc"][0])) + (f" /{inner}" if inner else ""), first["msg"]) from None


SHOWN_ELSEWHERE = ("analysis", "name", "status", "message", "iterations", "seconds", "warnings")


def _named_numbers(value: Any) -> bool:
    return (
        isinstance(value, dict)
        and bool(value)
        and all(isinstance(v, (int, float)) and not isinstance(v, bool) or v is None for v in value.values())
    )


def _scalar_record(row: dict) -> bool:
    """Every field of a record shows in its table's row (else --json has more)."""
    return all(v is None or isinstance(v, (int, float, str)) for v in row.values())


def print_report(out: Console, report: dict) -> None:
    """The status; then each number, each quantity ({value, unit}) and a table per mapping of
    named numbers (its units from the report's <key>_units); the rest is named as in --json."""
    print_status(out, report)
    rest = []
    for key, value in report.items():
        if key in SHOWN_ELSEWHERE or key.endswith(("units", "_unit")):
            continue
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            unit = report.get(f"{key}_unit") or report.get(f"{key.rsplit('_', 1)[0]}_unit")
            out.print(f"{shown(key)}: {number(value, unit if isinstance(unit, str) else None)}")
        elif isinstance(value, str):
            out.print(f"{shown(key)}: {shown(value)}")
        elif isinstance(value, dict) and "value" in value and "unit" in value:
            status = f" ({value['status']})" if "status" in value else ""
            out.print(f"{shown(key)}: {number(value['value'], value['unit'])}{shown(status)}")
        elif _named_numbers(value):
            units = report.get(f"{key.removesuffix('s')}_units") or {}
            table = table_of(key, "name", "value", "unit", text=1)
            for name, v in value.items():
                table.add_row(
                    shown(name), number(v), shown(str(units.get(name, "") if isinstance(units, dict) else ""))
                )
            out.print(table)
        elif is_records(value):
            units = report.get("units")
            out.print(records_table(key, value, units if isinstance(units, dict) else {}))
            if any(not _scalar_record(row) for row in value):
                rest.append(key)
        elif value not in (None, [], {}):
            rest.append(key)
    for note in report.get("warnings", []):
        out.print(f"[yellow]warning:[/yellow] {shown(note)}")
    if rest:
        out.print(f"also in the report (--json): {shown(', '.join(rest))}")


def run_command(
    analysis: Analysis,
    document: Path,
    model: str | None,
    sets: list[str] | None,
    jacobian: str,
    line_search: bool,
    max_iterations: int,
    json_out: Path | None,
    given: dict[str, Any],
    figures: dict[str, Path | None] | None = None,
) -> None:
    out, err = consoles()
    with user_errors(err):
        wanted = {flag: checked_figure(analysis, flag, path) for flag, path in (figures or {}).items() if path}
        options = typed_options(analysis, given)
        newton = newton_options(jacobian, line_search, max_iterations)
        mech = mechanism(document, model, sets)
        report = analysis.run(mech, AnalysisRequest(newton, options))
        out.print(f"[bold]{shown(mech.document.name)}[/bold]  ({shown(str(document))}): {analysis.name}")
        print_report(out, report)
        if json_out is not None:
            write_json(json_out, {"document": str(document), "model": model, **report})
            out.print(f"wrote {shown(str(json_out))}")
        if report.get("status") in FINE:
            for flag, path in wanted.items():
                analysis.draw(mech, newton, options, report, flag, path)
                out.print(f"wrote {shown(str(path))}")
    if report.get("status") not in FINE:
        raise typer.Exit(EXIT_NOT_CONVERGED)


def command_of(analysis: Analysis):
    """The command function, its signature made from the options model (typer reads it)."""
    option_names = list(analysis.Options.model_fields)

    def command(**kwargs: Any) -> None:
        common = {name: kwargs.get(name, COMMON_DEFAULTS.get(name)) for name, _ in COMMON}
        figures = {flag: kwargs.get(f"figure_{flag}") for flag, _, _ in analysis.figures}
        run_command(analysis, **common, given={name: kwargs.get(name) for name in option_names}, figures=figures)

    parameters = [
        inspect.Parameter(
            name,
            inspect.Parameter.KEYWORD_ONLY,
            annotation=annotation,
            default=COMMON_DEFAULTS.get(name, inspect.Parameter.empty),
        )
        for name, annotation in COMMON
    ]
    parameters += [
        option_parameter(name, analysis.Options.model_fields[name])
        for name in option_names
        if name not in COMMON_DEFAULTS and name != "document"
    ]
    parameters += [
        inspect.Parameter(
            f"figure_{flag}",
            inspect.Parameter.KEYWORD_ONLY,
            annotation=Annotated[
                Path | None, typer.Option(f"--{flag}", metavar=f"OUT{'|'.join(suffixes)}", help=help_text)
            ],
            default=None,
        )
        for flag, suffixes, help_text in analysis.figures
    ]
    command.__signature__ = inspect.Signature(parameters)  # type: ignore[attr-defined]
    command.__annotations__ = {p.name: p.annotation for p in parameters}
    command.__doc__ = f"{analysis.summary}. Its options are the flags below (as fields of POST /v1/solve)."
    return command


def checked_figure(analysis: Analysis, flag: str, path: Path) -> Path:
    """The figure's path, OptionError at its flag unless its suffix is one the figure takes."""
    suffixes = next(suffixes for name, suffixes, _ in analysis.figures if name == flag)
    if path.suffix.lower() not in suffixes:
        raise OptionError(
            f"--{flag}", f"cannot tell the format of '{path}': use a name ending in {' or '.join(suffixes)}"
        )
    return path


def commands_of(analyses: Analyses, taken: Collection[str]) -> dict[str, Any]:
    """Command name -> command of every analysis whose name (and of each alias) no command in
    `taken` has (api.cli.commands lists them after the modules' own commands)."""
    maker = typer.Typer(add_completion=False)
    for command, name, short in command_names(((a.name, a.summary, a.aliases) for a in analyses), taken):
        function = command_of(analyses.named(name))
        maker.command(name=command, help=function.__doc__, short_help=short)(function)
    return dict(typer.main.get_group(maker).commands) if maker.registered_commands else {}
