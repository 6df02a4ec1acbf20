"""The page shows numbers by the command line's rules: api/web/display.js, run by Node, gives
the same display unit and the same text as service/display.py for every case below (stresses,
masses, energies, frequencies, round-off beside results, ratios, squared units, counts, the
exponent form's edges), and a table's head names the display unit its column is shown in."""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

from flexmech.service.display import display, exact, number_text

DISPLAY_JS = Path(__file__).resolve().parents[2] / "api" / "web" / "display.js"
CASES = [
    ("GPa", [0.00146703, 0.0427648, 0.188765], None),
    ("kg", [1.21946e-09], None),
    ("kg", [2.85098e-10, 6.19788e-12, 1.91919e-13], None),
    ("uN*mm", [4.77266], "energy"),
    ("N*m", [317.873e-3], "energy"),
    ("mm", [0.651337, 3.55271e-16, -0.0278975], None),
    ("Hz", [56789.2, 2200.03], None),
    ("s", [0.000454539, 1.7609e-05], None),
    ("uN", [77.0346, -60.0], None),
    ("mm/N", [6.6666e-2, -1.36457e-30], None),
    ("mm/GPa", [-0.0173553, -3.01e-13], "ratio"),
    ("mm^2", [1e-4], None),
    ("deg", [20.1106, 1e-18], None),
    ("", [3, 14, 100], None),
    ("m", [0.0, 0.0], None),
]
NUMBERS = [77.03456, -6.92779e-15, 1e6, 123456.7, 999999.7, 0.5, 1.234e-5, 0.0001234, 2.46204e-13, 99999.95]


def _node(script: str, tmp_path: Path) -> object:
    node = shutil.which("node") or shutil.which("nodejs")
    assert node, "Node.js runs the page's modules in this test (apt install nodejs)"
    module = tmp_path / "display.mjs"  # an ES module by its suffix, as the browser loads it
    module.write_text(DISPLAY_JS.read_text())
    runner = tmp_path / "run.mjs"
    runner.write_text(f'import * as shown from "{module.as_uri()}";\n{script}')
    done = subprocess.run([node, str(runner)], capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)


def test_the_page_shows_each_quantity_as_the_command_line_does(tmp_path):
    script = f"""
const cases = {json.dumps(CASES)};
const numbers = {json.dumps(NUMBERS)};
console.log(JSON.stringify({{
  displays: cases.map(([unit, values, kind]) => {{ const d = shown.display(unit, values, kind); return [d.unit, values.map((v) => d.text(v))]; }}),
  numbers: numbers.map((v) => shown.numberText(v)),
  exact: numbers.map((v) => shown.exactText(v)),
}}));
"""
    page = _node(script, tmp_path)
    for (unit, values, kind), (js_unit, js_texts) in zip(CASES, page["displays"]):
        python = display(unit, values, kind)
        assert (js_unit, js_texts) == (python.unit, [python.text(v) for v in values]), (unit, values, kind)
    assert page["numbers"] == [number_text(v) for v in NUMBERS]
    assert page["exact"] == [exact(v) for v in NUMBERS]
    # the figures issue 49 names, as both show them
    assert page["displays"][0] == ["MPa", ["1.46703", "42.7648", "188.765"]]
    assert page["displays"][3] == ["nJ", ["4.77266"]]
    assert page["displays"][5][1][1] == "0"  # the closing point's round-off


def test_a_tables_head_names_the_unit_its_column_is_shown_in(tmp_path):
    """shownTable: a column by its head's unit, a table with a unit column by row; residuals
    exact."""
    table = {
        "columns": ["flexure", "σ max [GPa]", "mass (kg)", "residual [uN]"],
        "rows": [["a", 0.110624, 2.85e-10, 2.46204e-13], ["d", 0.188765, 1.9e-13, 1e-14]],
    }
    by_row = {"columns": ["field", "value", "unit"], "rows": [["m", 1.21946e-09, "kg"], ["f", 77.0346, "uN"]]}
    script = (
        f"console.log(JSON.stringify([shown.shownTable({json.dumps(table)}), shown.shownTable({json.dumps(by_row)})]));"
    )
    columns, rows = _node(script, tmp_path)
    assert columns["columns"] == ["flexure", "σ max [MPa]", "mass (ng)", "residual [uN]"]
    assert columns["rows"][1] == ["d", "188.765", "0.19", "1e-14"]  # 1.9e-13 kg is 0.19 ng
    assert columns["numeric"][0] == [False, True, True, True]
    assert rows["rows"] == [["m", "1.21946", "ug"], ["f", "77.0346", "uN"]]
