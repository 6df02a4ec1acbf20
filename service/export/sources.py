"""The C sources of an export: the CasADi-generated kernels (made warning-free under
-Wall -Wextra), and the driver, header, examples and build files filled from templates.

Every template value made of a document's string goes through one encoder of
service.export.encoders, chosen by where it lands; its key says which: *_COMMENT (C comment),
*_STRING (C string literal), *_MAKE (Makefile and CMake comment), *_DOC (Python docstring);
NAME, UPPER and the lines of macros are made of C identifiers. A template is filled in one pass,
so a value is never read again for placeholders."""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from importlib.resources import files
from pathlib import Path

import casadi as ca

from flexmech.service.export.encoders import c_comment, c_macro, c_string, hash_comment, python_docstring
from flexmech.service.export.kernels import ExportFunctions
from flexmech.service.export.plan import ExportPlan

TEMPLATES = files("flexmech.service.export") / "templates"
_UNUSED = re.compile(r"^(?:static |CASADI_SYMBOL_EXPORT )[^;=]*?\b\w+\(([^()]*)\)\s*\{\s*$")
_PLACEHOLDER = re.compile(r"@([A-Z_0-9]+)@")
DESCRIPTION_LIMIT = 2000  # characters of a comment the export composes (paths, targets): names of 64 at most


@dataclass(frozen=True)
class ExamplePath:
    """The path the example, the benchmark and the checks run through `task` (equilibrium or
    contact): inputs `indices` move together from `starts` to `stops` (document units) in
    `points` points."""

    indices: tuple[int, ...]
    starts: tuple[float, ...]
    stops: tuple[float, ...]
    points: int = 100
    task: str = "equilibrium"

    def values(self, defaults) -> list[list[float]]:
        """The inputs at each point (defaults elsewhere)."""
        rows = []
        for t in [i / (self.points - 1) for i in range(self.points)]:
            row = list(defaults)
            for k, a, b in zip(self.indices, self.starts, self.stops):
                row[k] = a + (b - a) * t
            rows.append(row)
        return rows


def c_double(value: float) -> str:
    if math.isinf(value):
        return "INFINITY" if value > 0 else "-INFINITY"
    return repr(float(value))


def _mark_unused(source: str) -> str:
    """CasADi gives every function the same signature (arg, res, iw, w, mem) whether it reads
    them or not; a (void) cast per parameter keeps -Wunused-parameter quiet without switching
    any warning off."""
    out = []
    for line in source.splitlines(keepends=True):
        out.append(line)
        match = _UNUSED.match(line.rstrip("\n"))
        if match and match.group(1).strip() not in ("", "void"):
            names = [re.findall(r"\w+", a)[-1] for a in match.group(1).split(",")]
            out.append("  " + " ".join(f"(void){n};" for n in names) + "\n")
    return "".join(out)


def write_kernels(functions: ExportFunctions, name: str, folder: Path) -> Path:
    generator = ca.CodeGenerator(f"{name}_kernels.c", {"with_header": True, "casadi_int": "long long int"})
    for f in functions.all():
        generator.add(f)
    generator.generate(str(folder) + "/")
    source = folder / f"{name}_kernels.c"
    source.write_text(_mark_unused(source.read_text()))
    return source


def work_sizes(functions: ExportFunctions) -> dict[str, int]:
    fs = functions.all()
    return {
        "SZ_ARG": max(3, *(f.sz_arg() for f in fs)),
        "SZ_RES": max(2, *(f.sz_res() for f in fs)),
        "SZ_IW": max(1, *(f.sz_iw() for f in fs)),
        "SZ_W": max(1, *(f.sz_w() for f in fs)),
    }


def fill(template: str, values: dict[str, str]) -> str:
    """The template with every @KEY@ replaced by its value, in one pass: a value that holds
    "@KEY@" (a title can) stays as it is."""
    text = (TEMPLATES / template).read_text()
    left = sorted({key for key in _PLACEHOLDER.findall(text) if key not in values})
    if left:
        raise RuntimeError(f"template {template}: unfilled {', '.join(left)}")
    return _PLACEHOLDER.sub(lambda match: values[match.group(1)], text)


def _lines(items: list[tuple[str, str]]) -> str:
    return "\n".join(f"{a}{b}" for a, b in items)


def _io_values(plan: ExportPlan, coordinates) -> dict[str, str]:
    """The header's lines naming every input, output and stiffness coordinate: macros of C
    identifiers, comments of the document's pointers, names and units."""
    return {
        "INPUT_LINES": _lines(
            [
                (
                    f"#define {c_macro(plan.name, 'in', i.c_name)} {k}",
                    f" /* {c_comment(f'{i.pointer} [{i.unit}], {_range(i)}')} */",
                )
                for k, i in enumerate(plan.inputs)
            ]
        ),
        "OUTPUT_LINES": _lines(
            [
                (f"#define {c_macro(plan.name, 'out', o.c_name)} {k}", f" /* {c_comment(f'{o.name} [{o.unit}]')} */")
                for k, o in enumerate(plan.outputs)
            ]
        ),
        "COORDINATE_LINES": _lines(
            [
                (" *   ", c_comment(f"{k}: {c['name']} [{c['unit']}], row: {c['force_unit']}"))
                for k, c in enumerate(coordinates)
            ]
        ),
    }


def _target_values(plan: ExportPlan) -> dict[str, str]:
    target = plan.target
    if target is None:
        return {"TARGET_GOAL": "0.0", "TARGET_COMMENT": "none in this export (returns NO_TARGET)."}
    solved, output = plan.inputs[target.input], target.output
    return {
        "TARGET_GOAL": c_double(target.default_goal),
        "TARGET_COMMENT": c_comment(
            f"the value of input {solved.c_name} [{solved.unit}] at which {output.name} [{output.unit}] equals goal.",
            DESCRIPTION_LIMIT,
        ),
        "TARGET_INPUT_STRING": c_string(solved.c_name),
        "TARGET_INPUT_UNIT_STRING": c_string(solved.unit),
        "TARGET_OUTPUT_STRING": c_string(output.name),
        "TARGET_OUTPUT_UNIT_STRING": c_string(output.unit),
        "TARGET_INDEX": str(target.input),
        "TARGET_FIRST_GUESS": c_double(solved.default),
    }


def _path_values(plan: ExportPlan, functions: ExportFunctions, path: ExamplePath) -> dict[str, str]:
    """The example path: how main.c, bench.c and check.c set the inputs at fraction t."""
    first = plan.inputs[path.indices[0]]
    moved = ", ".join(
        f"{plan.inputs[k].c_name} from {a:.10g} to {b:.10g} {plan.inputs[k].unit}"
        for k, a, b in zip(path.indices, path.starts, path.stops)
    )
    if path.task == "contact" and functions.contact is not None:
        labels = [f"{n} [{u}]" for n, u in zip(functions.contact.names, functions.contact.units)]
        count = c_macro(plan.name, "n_contact_outputs")
    else:
        labels = [f"{o.name} [{o.unit}]" for o in plan.outputs]
        count = c_macro(plan.name, "n_outputs")
    return {
        "PATH_TASK": path.task,
        "PATH_POINTS": str(path.points),
        "PATH_FIRST": str(path.indices[0]),
        "PATH_LABEL_STRING": c_string(f"{first.c_name} [{first.unit}]"),
        "PATH_COMMENT": c_comment(f"{path.points} points: {moved}", DESCRIPTION_LIMIT),
        "PATH_N_OUTPUTS": count,
        "PATH_OUTPUT_STRINGS": ", ".join(c_string(label) for label in labels),
        "SET_PATH": "\n".join(
            f"    in[{k}] = {c_double(a)} + ({c_double(b)} - ({c_double(a)})) * t;"
            for k, a, b in zip(path.indices, path.starts, path.stops)
        ),
    }


def _contact_values(plan: ExportPlan, functions: ExportFunctions) -> dict[str, str]:
    contact = functions.contact
    chosen = plan.contact_outputs if contact else ()
    units = contact.units if contact else ()
    if contact and tuple(c.name for c in chosen) != tuple(contact.names):
        raise RuntimeError(f"the contact task's outputs {contact.names} are not the plan's")
    return {
        "HAS_CONTACT": "1" if contact else "0",
        "NV": str(max(1, contact.n_v if contact else 0)),
        "N_CONTACT_OUTPUTS": str(len(chosen)),
        "CONTACT_OUTPUT_LINES": _lines(
            [
                (f"#define {c_macro(plan.name, 'contact', c.c_name)} {k}", f" /* {c_comment(f'{c.name} [{u}]')} */")
                for k, (c, u) in enumerate(zip(chosen, units))
            ]
        ),
        "CONTACT_NOTE": "frictionless; forces are the contact multipliers" if contact else "none in this export",
    }


def template_values(
    plan: ExportPlan, functions: ExportFunctions, p_default, coordinates, path: ExamplePath, meta: dict
) -> dict[str, str]:
    """Every @KEY@ of the templates."""
    n = functions.eq_step.size1_in(0)
    values = {
        "NAME": plan.name,
        "UPPER": c_macro(plan.name),
        "TITLE_COMMENT": c_comment(meta["title"]),
        "TITLE_MAKE": hash_comment(meta["title"]),
        "TITLE_DOC": python_docstring(meta["title"]),
        "VERSION": meta["version"],
        "MODEL_COMMENT": c_comment(plan.model),
        "NP": str(len(p_default)),
        "N": str(n),
        "N1": str(n + 1),
        "DEFAULT_P": ", ".join(c_double(v) for v in p_default),
        "INPUT_SLOTS": ", ".join(str(i.slot) for i in plan.inputs),
        "INPUT_SCALES": ", ".join(c_double(i.nd_per_unit) for i in plan.inputs),
        "INPUT_LOWS": ", ".join(c_double(i.low) for i in plan.inputs),
        "INPUT_HIGHS": ", ".join(c_double(i.high) for i in plan.inputs),
        "INPUT_LOW_EXCLUDED": ", ".join(str(int(i.low_excluded)) for i in plan.inputs),
        "INPUT_DEFAULTS": ", ".join(c_double(i.default) for i in plan.inputs),
        "TOLERANCE": c_double(plan.options.tolerance),
        "HALVINGS": str(plan.options.line_search_halvings),
        "MAX_ITERATIONS": str(plan.options.max_iterations),
        "N_INPUTS": str(len(plan.inputs)),
        "N_OUTPUTS": str(len(plan.outputs)),
        "N_COORDINATES": str(len(coordinates)),
        **{k: str(v) for k, v in work_sizes(functions).items()},
        **_io_values(plan, coordinates),
        **_target_values(plan),
        **_path_values(plan, functions, path),
        **_contact_values(plan, functions),
    }
    values["NMAX"] = str(max(n + 1, int(values["NV"])))
    return values


def _range(item) -> str:
    low = ("(" if item.low_excluded else "[") + (c_double(item.low) if math.isfinite(item.low) else "-inf")
    high = (c_double(item.high) if math.isfinite(item.high) else "inf") + "]"
    return f"range {low}, {high}"


def write_sources(plan: ExportPlan, values: dict[str, str], folder: Path) -> list[Path]:
    """The driver, header, example, benchmark, checks, build files and loader."""
    target_code = fill("target.c.in" if plan.target else "no_target.c.in", values)
    contact_code = fill("contact.c.in" if values["HAS_CONTACT"] == "1" else "no_contact.c.in", values)
    target_example = fill("main_target.c.in", values) if plan.target is not None else ""
    written = {
        f"{plan.name}.c": fill("driver.c.in", {**values, "TARGET_CODE": target_code, "CONTACT_CODE": contact_code}),
        f"{plan.name}.h": fill("header.h.in", values),
        "main.c": fill("main.c.in", {**values, "TARGET_EXAMPLE": target_example}),
        "bench.c": fill("bench.c.in", values),
        "check.c": fill("check.c.in", values),
        "Makefile": fill("Makefile.in", values),
        "CMakeLists.txt": fill("CMakeLists.txt.in", values),
        "loader.py": fill("loader.py.in", values),
    }
    paths = []
    for file_name, text in written.items():
        path = folder / file_name
        path.write_text(text)
        paths.append(path)
    return paths
