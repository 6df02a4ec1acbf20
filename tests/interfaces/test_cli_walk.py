"""The walk of issue 49: every shipped example through every analysis the service offers it
(`flexmech solve DOC --analysis A`, printed as the analysis' own command prints it) and through
the commands with their own tables (sweep, trace, inverse, optimize, contact, modes, frf,
linearize, simulate), read as an engineer reads the terminal: each numeric column says its
unit (or is a count or a relative measure), no number in a table is below 1e-12 in magnitude
(round-off is 0; residual and tolerance lines keep their exact values), no name is cut short,
and nothing ends in a traceback."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from typer.testing import CliRunner

from flexmech import load
from flexmech.api.cli import app
from flexmech.service.offers import offers

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
ENV = {"COLUMNS": "400", "NO_COLOR": "1"}
NUMBER = re.compile(r"(?<![\w.])[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?(?![\w.])")
# numeric columns that need no unit: counts and indices, and measures that say they are relative
UNITLESS = ("point", "mode", "iterations", "after point", "impact", "quality", "case", "steps", "count")
RELATIVE = ("relative", "ratio", "%", "fraction", "rebound")
COMMANDS = [
    ("sweep", "gripper.json"),
    ("sweep", "six_bar.json"),
    ("trace", "snap_through_arch.json", "--path", "/loads/P/force/1", "--stop", "-300", "--step", "20"),
    ("inverse", "inverse_four_bar.json"),
    ("optimize", "gripper_sections.json"),
    ("contact", "two_finger_grip.json"),
    ("modes", "gripper_modes.json", "--count", "10"),
    ("frf", "gripper_modes.json", "--input", "/loads/actuation/force/1", "--output", "end_effector.x"),
    ("linearization", "gripper.json", "--at", "undeformed"),
    ("linearize", "rod_free_vibration.json", "--state-space", "{tmp}/rod.json"),
    ("simulate", "four_bar_dynamics.json"),
    ("simulate", "csfh_central_impact.json"),
    ("solve", "gripper.json", "--stiffness"),
]


def _tables(text: str) -> list[tuple[list[str], list[list[str]]]]:
    """(heads, rows) of each box table in rich's output (one line per head: a wide console)."""
    tables, heads, rows = [], None, []
    for line in text.splitlines():
        if line.startswith("┃"):
            heads = [cell.strip() for cell in line.strip("┃").split("┃")]
        elif line.startswith("│") and heads is not None:
            rows.append([cell.strip() for cell in line.strip("│").split("│")])
        elif line.startswith("└") and heads is not None:
            tables.append((heads, rows))
            heads, rows = None, []
    return tables


def _is_number(cell: str) -> bool:
    return cell == "-" or NUMBER.fullmatch(cell) is not None


def problems_of(text: str) -> list[str]:
    """What an engineer would trip over in one command's output."""
    found = []
    if "Traceback" in text or "╭─ Traceback" in text or "Error ─" in text:
        found.append("a traceback or a usage error box")
    if "…" in text:
        found.append("a name cut short (…)")
    for heads, rows in _tables(text):
        if "unit" in heads:  # a table whose unit varies by row has a column of units
            continue
        for k, head in enumerate(heads):
            cells = [row[k] for row in rows if k < len(row)]
            if not cells or not all(_is_number(c) for c in cells) or all(c == "-" for c in cells):
                continue
            has_unit = re.search(r"[\[(][^\])]+[\])]$", head) is not None
            lowered = head.lower()
            if not has_unit and lowered not in UNITLESS and not any(word in lowered for word in RELATIVE):
                found.append(f"numeric column {head!r} without a unit")
    for line in text.splitlines():
        if "residual" in line or "tolerance" in line:
            continue
        for token in NUMBER.findall(line):
            value = float(token)
            if 0 < abs(value) < 1e-12:
                found.append(f"round-off {token} shown in: {line.strip()[:120]}")
    return found


def _offered(path: Path) -> list[str]:
    return [name for name, why_not in offers(load(path))["analyses"].items() if why_not is None]


def _run(args: list[str]) -> tuple[int, str]:
    result = CliRunner().invoke(app, args, env=ENV)
    return result.exit_code, result.output


def test_the_walk_reads_problems_as_problems():
    """The walk's own reading fails on what it is meant to catch (a check that could not fail
    would prove nothing)."""
    table = (
        "┏━━━┳━━━━━━━━━━━━┳━━━━━━━┓\n┃ a ┃ mass       ┃ x [mm]┃\n┡━━━╇━━━━━━━━━━━━╇━━━━━━━┩\n"
        "│ p │ 1.2e-09    │ 3.5e-16 │\n└───┴────────────┴───────┘\n"
    )
    found = problems_of(table + "a name cut shor…\n")
    assert "numeric column 'mass' without a unit" in found
    assert any(p.startswith("round-off 3.5e-16") for p in found)
    assert "a name cut short (…)" in found
    assert problems_of("status: converged, residual 2.46e-13 uN\n") == []


@pytest.mark.parametrize("example", sorted(p.name for p in EXAMPLES.glob("*.json")))
def test_every_offered_analysis_of_every_example_reads_as_an_engineers_result(example):
    """Each analysis the service offers the example, through `flexmech solve --analysis`: a
    result (exit 0), a status that is not one (1), or one line naming what the analysis needs
    (2, e.g. a frequency response's input); in each case the output passes problems_of."""
    path = EXAMPLES / example
    for analysis in _offered(path):
        code, text = _run(["solve", str(path), "--analysis", analysis])
        assert code in (0, 1, 2), (analysis, text[-2000:])
        if code == 2:
            assert text.strip().startswith("error: /"), (analysis, text[-2000:])  # the field, then the problem
        assert problems_of(text) == [], (analysis, problems_of(text), text[-3000:])


@pytest.mark.parametrize("command", COMMANDS, ids=lambda c: f"{c[0]}-{c[1]}")
def test_every_command_with_tables_of_its_own_reads_as_an_engineers_result(command, tmp_path):
    """The commands whose tables are their own, on an example that has what they need."""
    name, example, *rest = command
    args = [name, str(EXAMPLES / example), *(a.replace("{tmp}", str(tmp_path)) for a in rest)]
    code, text = _run(args)
    assert code == 0, text[-3000:]
    assert problems_of(text) == [], (problems_of(text), text[-4000:])


def test_the_acceptance_lines_print_stresses_in_mpa_masses_in_micrograms_and_energy_in_joules():
    """Issue 49 Acceptance 1 and 2 on the gripper: stresses in MPa, the strain energy in nJ, the
    modes' masses in ug or ng, residual_moment with a moment unit, K_T from linearization."""
    _, solved = _run(["solve", str(EXAMPLES / "gripper.json")])
    assert "σ max [MPa]" in solved and "strain energy: 4.77266 nJ" in solved
    assert "188.765" in solved  # flexure d's largest stress, 0.188765 GPa
    _, modes = _run(["modes", str(EXAMPLES / "gripper_modes.json"), "--count", "10"])
    assert "total_mass: 1.21946 ug" in modes
    assert re.search(r"effective_mass x \((ng|ug)\)", modes)
    assert re.search(r"residual_moment: [-\d.e]+ uN\*mm", modes)
    _, linear = _run(["linearization", str(EXAMPLES / "gripper.json"), "--at", "undeformed"])
    assert "tangent stiffness K_T" in linear and "input.x [uN]" in linear


def test_a_unit_of_the_wrong_kind_is_named_in_english():
    """'3 mm' for an angle: "is not an angle" (issue 49 found "is not a angle")."""
    import json

    from flexmech import MechanismError

    document = json.loads((EXAMPLES / "gripper.json").read_text())
    document["bodies"]["input"]["angle"] = "3 mm"
    with pytest.raises(MechanismError) as raised:
        load(document)
    assert "'3 mm' is not an angle (expected units like deg)" in str(raised.value)
