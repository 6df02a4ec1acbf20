# ruff: noqa: F811 (the fixtures imported from workbench are arguments of the tests)
"""The drawing in a real Chromium: the stress along every flexure as a colour map with its scale,
unit and the material's limit (stressmap.js), and zoom and pan (zoom.js), at 1400x900 and on a
phone."""

from __future__ import annotations

import json

import pytest
from browser import screenshot
from conftest import EXAMPLES
from workbench import (  # noqa: F401 (fixtures by name)
    browser,
    log,
    open_example,
    page,
    server,
    set_document_text,
)

FOLD = {"width": 1400, "height": 900}
SHOWN = 2e-3  # relative: the Outputs table shows four significant digits

OUTPUT_VALUES = """() => {
  const table = [...document.querySelectorAll('#panel-table table')].find((t) => t.caption && t.caption.textContent.startsWith('Outputs'));
  const values = {};
  for (const row of table.tBodies[0].rows) values[row.cells[0].textContent] = [Number(row.cells[1].textContent.replace('\\u2212', '-')), row.cells[row.cells.length - 1].textContent];
  return values;
}"""
IN_GPA = {"GPa": 1.0, "MPa": 1e-3}  # a shown stress's unit, in the document's
DRAWN = """() => [...document.querySelectorAll('#drawing g.stressed')].map((g) => ({
  name: g.dataset.stressed,
  largest: Number(g.dataset.stressMax),
  segments: [...g.querySelectorAll('path[data-stress]')].map((p) => Number(p.dataset.stress)),
  colours: new Set([...g.querySelectorAll('path[data-stress]')].map((p) => p.getAttribute('stroke'))).size,
  title: g.querySelector('[data-element] title').textContent,
}))"""


def solved(page, example: str) -> None:
    """Open an example, run its equilibrium, and wait for the stresses on the drawing."""
    page.evaluate("() => { document.body.dataset.offered = ''; }")
    open_example(page, example)
    page.wait_for_function("() => document.body.dataset.offered")
    page.select_option("#analysis", "solve:equilibrium")
    page.click("#run")
    page.wait_for_function("() => document.getElementById('result-card').dataset.status === 'ok'", timeout=120_000)
    page.wait_for_selector("#drawing g.stressed", timeout=60_000)


def test_the_gripper_equilibrium_is_coloured_by_its_flexures_stress(page):
    page.set_viewport_size(FOLD)
    solved(page, "gripper")
    bar = page.locator("#drawing .colour-bar")
    assert bar.count() == 1
    assert page.text_content("#drawing .colour-bar-title") == "stress [MPa]"  # 0.19 GPa shown as the tables show it
    assert page.locator("#drawing .colour-bar .limit-mark").count() == 0  # gripper.json gives no limit
    drawn, outputs = page.evaluate(DRAWN), page.evaluate(OUTPUT_VALUES)
    assert sorted(d["name"] for d in drawn) == ["a", "b", "c", "d"]
    for element in drawn:
        assert max(element["segments"]) == element["largest"]
        value, unit = outputs[f"elements.{element['name']}.stress_max"]
        assert element["largest"] == pytest.approx(value * IN_GPA[unit], rel=SHOWN)  # data-stress in the document's GPa
        assert element["colours"] > 3  # a map, not one colour
        assert "largest stress" in element["title"] and "MPa" in element["title"]
    top = float(bar.get_attribute("data-top"))
    assert top == pytest.approx(max(d["largest"] for d in drawn))
    screenshot(page, "drawing-gripper-stress")


def test_the_sections_gripper_marks_silicons_limit_on_the_scale(page):
    page.set_viewport_size(FOLD)
    solved(page, "gripper_sections")
    mark = page.locator("#drawing .colour-bar .limit-mark")
    assert mark.count() == 1 and float(mark.get_attribute("data-limit")) == pytest.approx(0.4)
    largest = max(d["largest"] for d in page.evaluate(DRAWN))
    over = page.locator("#drawing path.over-limit").count()
    assert (over > 0) == (largest > 0.4)
    assert float(page.get_attribute("#drawing .colour-bar", "data-top")) == pytest.approx(max(0.4, largest))
    screenshot(page, "drawing-sections-limit")


def test_flexures_above_their_limit_are_drawn_in_the_warning_style(page):
    """silicon's limit set to 0.1 GPa, below the sections gripper's largest stress (0.19 GPa)."""
    page.set_viewport_size(FOLD)
    solved(page, "gripper_sections")
    document = json.loads((EXAMPLES / "gripper_sections.json").read_text())
    document["materials"]["silicon"]["stress_limit"] = 0.1
    set_document_text(page, json.dumps(document, indent=2))
    page.wait_for_selector("#drawing g.stressed", state="detached")  # the edit redraws it undeformed
    page.click("#run")
    page.wait_for_function("() => document.getElementById('result-card').dataset.status === 'ok'", timeout=120_000)
    page.wait_for_selector("#drawing path.over-limit", timeout=60_000)
    for element in page.evaluate(DRAWN):
        over = [s for s in element["segments"] if s > 0.1]
        drawn_over = page.locator(f'#drawing g.stressed[data-stressed="{element["name"]}"] path.over-limit').count()
        assert drawn_over == len(over)
        assert ("exceeded" in element["title"]) == bool(over)
    assert float(page.get_attribute("#drawing .limit-mark", "data-limit")) == pytest.approx(0.1)
    screenshot(page, "drawing-over-limit")


def view_of(page) -> list[float]:
    return [float(v) for v in page.get_attribute("#drawing svg", "data-view").split()]


def test_zoom_and_pan_change_the_view_and_reset_restores_it(page):
    page.set_viewport_size(FOLD)
    solved(page, "gripper")
    whole = view_of(page)
    page.get_by_role("button", name="Zoom in").focus()
    page.keyboard.press("Enter")  # reachable by keyboard
    zoomed = view_of(page)
    assert zoomed[2] - zoomed[0] == pytest.approx((whole[2] - whole[0]) / 1.5, rel=1e-4)
    box = page.locator("#drawing svg").bounding_box()
    x, y = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
    page.mouse.move(x, y)
    page.mouse.down()
    page.mouse.move(x + 60, y + 30, steps=4)
    page.mouse.up()
    page.wait_for_function(
        "v => document.querySelector('#drawing svg').dataset.view !== v", arg=" ".join(map(str, zoomed))
    )
    panned = view_of(page)
    assert panned[0] < zoomed[0] and panned[1] > zoomed[1]  # dragged right and down: the view moves left and up
    assert panned[2] - panned[0] == pytest.approx(zoomed[2] - zoomed[0], rel=1e-6)
    page.mouse.move(x, y)
    page.mouse.wheel(0, -200)
    page.wait_for_function("z => Number(document.querySelector('#drawing svg').dataset.zoom) > z", arg=1.5)
    screenshot(page, "drawing-zoomed")
    page.get_by_role("button", name="Reset zoom: the whole drawing").click()
    assert view_of(page) == pytest.approx(whole)


def test_on_a_phone_the_scale_and_zoom_buttons_are_there(page):
    page.set_viewport_size({"width": 390, "height": 800})
    solved(page, "gripper_sections")
    assert page.locator("#drawing .colour-bar").is_visible()
    for name in ("Zoom in", "Zoom out", "Reset zoom: the whole drawing"):
        assert page.get_by_role("button", name=name).is_visible()
    page.locator("#drawing").scroll_into_view_if_needed()
    screenshot(page, "drawing-phone")
