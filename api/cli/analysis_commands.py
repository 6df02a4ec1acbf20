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

from flexmech.api.cli.catalog import alias_help, command_names
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
from flexmech.api.cli.problems import every_problem, in_the_file
from flexmech.api.cli.quantities import exact_text, kind_of
from flexmech.api.cli.record_tables import is_records, records_table
from flexmech.api.cli.report_tables import print_status, print_stiffness
from flexmech.api.cli.resonance_tables import resonance_tables
from flexmech.api.cli.tolerance_tables import print_tolerance
from flexmech.models import MechanismError
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


def is_names(info) -> bool:
    """A field that is a list of words, bounded or not (outputs, JSON pointers): a repeated flag."""
    kind = _plain(info.annotation)
    word = typing.get_args(kind)[0] if typing.get_origin(kind) is list else None
    return word is str or (typing.get_origin(word) is Annotated and typing.get_args(word)[0] is str)


def singular(name: str) -> str:
    if name.endswith("ies"):
        return name[:-3] + "y"
    return name[:-1] if name.endswith("s") and not name.endswith("ss") else name


def list_flags(fields: dict[str, Any]) -> dict[str, str]:
    """Field name -> its repeated flag, for each list of words: the singular of its name
    (--output for outputs) unless another field or a common option has that flag."""
    taken = {flag(name) for name in fields} | {flag(name) for name, _ in COMMON} | {"--set", "--json"}
    out = {}
    for name, info in fields.items():
        if is_names(info):
            one = flag(singular(name))
            out[name] = one if one not in taken else flag(name)
    return out


def option_flag(fields: dict[str, Any], name: str) -> str:
    """The flag a field is given by (a problem with the field is named by it)."""
    return list_flags(fields).get(name, flag(name))


def json_name(name: str) -> str:
    """The parameter of a list's JSON form (--outputs '["a", "b"]', as before the repeated flag)."""
    return f"{name}__json"


def option_parameters(name: str, info, fields: dict[str, Any]) -> list[inspect.Parameter]:
    """The flag of one options field: a bool is --x/--no-x, a number or a word takes its value,
    a choice names its choices, a list of words is a repeated flag (--output A --output B; its
    plural, hidden, still takes the list as JSON), anything else takes JSON."""
    kind = _plain(info.annotation)
    choices = typing.get_args(kind) if typing.get_origin(kind) is Literal else None
    hidden = None
    if kind is bool:
        annotation = Annotated[
            bool | None,
            typer.Option(f"{flag(name)}/--no-{name.replace('_', '-')}", help=_help(info, None), show_default=False),
        ]
    elif kind in (int, float, str) or choices:
        python = str if choices else kind
        annotation = Annotated[python | None, typer.Option(flag(name), help=_help(info, choices), show_default=False)]
    elif is_names(info):
        one = option_flag(fields, name)
        examples = info.examples[0] if info.examples and info.examples[0] else [""]
        metavar = "POINTER" if str(examples[0]).startswith("/") else "NAME"
        text = _help(info, None).removesuffix(".") + f"; one {metavar.lower()} per {one}, repeated."
        annotation = Annotated[list[str] | None, typer.Option(one, metavar=metavar, help=text, show_default=False)]
        if one != flag(name):
            hidden = inspect.Parameter(
                json_name(name),
                inspect.Parameter.KEYWORD_ONLY,
                default=None,
                annotation=Annotated[str | None, typer.Option(flag(name), metavar="JSON", hidden=True)],
            )
    else:
        annotation = Annotated[
            str | None, typer.Option(flag(name), metavar="JSON", help=_help(info, None), show_default=False)
        ]
    shown_one = inspect.Parameter(name, inspect.Parameter.KEYWORD_ONLY, default=None, annotation=annotation)
    return [shown_one] if hidden is None else [shown_one, hidden]


def given_names(fields: dict[str, Any], name: str, repeated: list[str] | None, as_json: str | None) -> list | None:
    """A list field's words from its repeated flag and its JSON form (a repeated flag's value
    that is a JSON list counts as its items); None when neither is given."""
    if repeated is None and as_json is None:
        return None
    words: list = []
    for item in repeated or []:
        words += _json_list(item, option_flag(fields, name)) if item.lstrip().startswith("[") else [item]
    if as_json is not None:
        words += _json_list(as_json, flag(name))
    return words


def _json_list(text: str, where: str) -> list:
    try:
        items = json.loads(text)
    except json.JSONDecodeError as exc:
        raise OptionError(where, f"not JSON: {exc.msg}") from None
    if not isinstance(items, list):
        raise OptionError(where, f'expected a JSON list like ["a", "b"], got {text!r}')
    return items


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
    """The options model from the flags given (JSON flags parsed, a list's repeated flag and its
    JSON form joined); OptionError names the flag."""
    fields = {}
    model = analysis.Options.model_fields
    for name, value in given.items():
        if name not in model:
            continue
        if is_names(model[name]):
            value = given_names(model, name, value, given.get(json_name(name)))
        if value is None:
            continue
        kind = _plain(model[name].annotation)
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
        where = option_flag(model, str(first["loc"][0]))
        raise OptionError(where + (f" /{inner}" if inner else ""), first["msg"]) from None


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
    named numbers (its units from the report's <key>_units); the tangent stiffness K_T and its
    terms as `flexmech solve --stiffness` prints them, the resonances with their units; the rest
    is named as in --json."""
    print_status(out, report)
    rest, shown_already = [], print_tolerance(out, report)
    for key, value in report.items():
        if key in SHOWN_ELSEWHERE or key.endswith(("units", "_unit")) or key in shown_already:
            continue
        if key == "stiffness" and isinstance(value, dict) and "K" in value:
            print_stiffness(out, value)
        elif key == "resonances" and is_records(value):
            for table in resonance_tables(report):
                out.print(table)
        elif isinstance(value, (int, float)) and not isinstance(value, bool):
            unit = report.get(f"{key}_unit") or report.get(f"{key.rsplit('_', 1)[0]}_unit")
            unit = unit if isinstance(unit, str) else None
            kind = kind_of(key)
            if unit == "nondimensional":
                out.print(f"{shown(key)}: {exact_text(value)} (nondimensional)")
            else:
                out.print(f"{shown(key)}: {shown(number(value, unit, kind=kind))}")
        elif isinstance(value, str):
            out.print(f"{shown(key)}: {shown(value)}")
        elif isinstance(value, dict) and "value" in value and "unit" in value:
            status = f" ({value['status']})" if "status" in value else ""
            text = number(value["value"], value["unit"], kind=kind_of(key))
            out.print(f"{shown(key)}: {shown(text)}{shown(status)}")
        elif _named_numbers(value):
            units = report.get(f"{key.removesuffix('s')}_units") or {}
            table = table_of(key, "name", "value", "unit", text=1, unit_column=(1, 2))
            for name, v in value.items():
                table.add_row(shown(name), v, str(units.get(name, "") if isinstance(units, dict) else ""))
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
        try:
            report = analysis.run(mech, AnalysisRequest(newton, options))
        except MechanismError as exc:
            raise named_by_flag(analysis, options, exc) from None
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


def named_by_flag(analysis: Analysis, options: Any, exc: MechanismError) -> Exception:
    """A problem the analysis names by a request's pointer, named as the command line has it:
    an option by its flag (an item of a repeated flag by its value: --output bodies.nope), a
    field of the document from the file's root (the request's /document/... is the file)."""
    parts = exc.pointer.split("/")[1:]
    fields = analysis.Options.model_fields
    if parts and parts[0] == "document":
        return every_problem(in_the_file(exc))
    if not parts or parts[0] not in fields:
        return every_problem(exc)
    where, value = option_flag(fields, parts[0]), getattr(options, parts[0], None)
    if is_names(fields[parts[0]]) and len(parts) > 1 and parts[1].isdigit() and int(parts[1]) < len(value or []):
        return OptionError(f"{where} {value[int(parts[1])]}", exc.problem)
    return OptionError(where + (f" /{'/'.join(parts[1:])}" if len(parts) > 1 else ""), exc.problem)


def command_of(analysis: Analysis):
    """The command function, its signature made from the options model (typer reads it)."""
    fields = analysis.Options.model_fields
    option_names = list(fields)

    def command(**kwargs: Any) -> None:
        common = {name: kwargs.get(name, COMMON_DEFAULTS.get(name)) for name, _ in COMMON}
        figures = {flag: kwargs.get(f"figure_{flag}") for flag, _, _ in analysis.figures}
        given = {name: kwargs.get(name) for name in option_names}
        given |= {json_name(name): kwargs.get(json_name(name)) for name in list_flags(fields)}
        run_command(analysis, **common, given=given, figures=figures)

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
        parameter
        for name in option_names
        if name not in COMMON_DEFAULTS and name != "document"
        for parameter in option_parameters(name, fields[name], fields)
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
        own = name.replace("_", "-")
        text = function.__doc__ if command == own else f"{alias_help(own)} {function.__doc__}"
        maker.command(name=command, help=text, short_help=short)(function)
    return dict(typer.main.get_group(maker).commands) if maker.registered_commands else {}
