# ruff: noqa: F811 (the fixtures imported from workbench are arguments of the tests)
"""Runs side by side and fields picked, in a real Chromium: the gripper's sweep in the three
curved-beam models kept for comparison on one plot (each ends at its own closing force), a run
in other units listed and not drawn; the arch's trace run with its path picked from the
document's fields; a load arrow or an element clicked in the drawing fills the path field."""

from __future__ import annotations

import pytest
from browser import SCREENSHOTS, screenshot
from conftest import ACTUATION, EXAMPLES
from workbench import (  # noqa: F401 (fixtures by name)
    browser,
    choose,
    log,
    open_example,
    page,
    run_and_wait,
    server,
)

from flexmech.models import COMPARED_MODELS, compile_mechanism, load_document
from flexmech.service import solve_for_target
from flexmech.service.solvers.continuation import trace_path

FOLD = {"width": 1400, "height": 900}
MODEL_NAMES = {"linear": "linear model", "partial_nonlinear": "partial non-linear model", "exact": "exact model"}
KEPT = "async () => (await import('/workbench/compare.js')).keptRuns()"


@pytest.fixture(scope="module")
def closing_forces() -> dict[str, float]:
    """The gripper's closing force (end_effector.x = 0) in each curved-beam model, by the core
    (63.95, 77.03 and 69.86 uN)."""
    forces = {}
    for model in COMPARED_MODELS:
        mech = compile_mechanism(load_document(EXAMPLES / "gripper.json"), model=model)
        forces[model] = solve_for_target(mech, ACTUATION, "end_effector.x", 0.0).value
    return forces


def run_job(page, timeout: float = 180_000) -> None:
    """Run the chosen job (the status line emptied first: the last run's words do not count)."""
    page.evaluate("() => { document.getElementById('run-state').textContent = ''; }")
    run_and_wait(page, "job succeeded", timeout=timeout)
    page.wait_for_function("() => document.getElementById('result-card').dataset.status === 'ok'")


def keep_closing_curve(page) -> None:
    """The end effector's x against the actuation force, kept for comparison."""
    page.click("#tab-curves")
    page.select_option("#curve-x", ACTUATION)
    page.select_option("#curve-y", "end_effector.x")
    page.click("#pin-curve")
    assert page.is_disabled("#pin-curve") and page.text_content("#pin-curve") == "Kept for comparison"


def test_the_three_curved_beam_models_sweeps_are_kept_on_one_plot(page, closing_forces):
    page.set_viewport_size(FOLD)
    choose(page, "job:sweep")
    page.fill("#option-outputs", "end_effector.x, end_effector.y")
    for model in COMPARED_MODELS:
        page.select_option("#model", model)
        run_job(page)
        keep_closing_curve(page)
    plot = page.locator("#curve svg.line-plot")
    assert plot.locator("path.plot-series").count() == 3
    legend = plot.locator(".plot-legend text").all_text_contents()
    assert len(legend) == 3
    for model, entry in zip(COMPARED_MODELS, legend, strict=True):
        assert entry.startswith(f"sweep job, {MODEL_NAMES[model]}, "), legend
    assert page.locator("#pinned-list li[data-drawn=true]").count() == 3
    kept = page.evaluate(KEPT)
    ends = {}
    for model, run in zip(COMPARED_MODELS, kept, strict=True):
        forces, x = run["series"][ACTUATION], run["series"]["end_effector.x"]
        assert run["units"][ACTUATION] == "uN" and run["units"]["end_effector.x"] == "mm"
        assert abs(x[-1]) < 1e-9  # each sweep runs until its gripper closes...
        ends[model] = forces[-1]  # ...at its own closing force
        assert ends[model] == pytest.approx(closing_forces[model], rel=1e-9)
    assert ends["linear"] == pytest.approx(63.95, abs=0.01)
    assert ends["partial_nonlinear"] == pytest.approx(77.03, abs=0.01)
    assert ends["exact"] == pytest.approx(69.86, abs=0.01)
    page.locator("#compare").scroll_into_view_if_needed()
    screenshot(page, "compare-three-models")
    plot.screenshot(path=str(SCREENSHOTS / "compare-three-models-plot.png"))

    # Another quantity on the axes: every kept run has it, all three follow.
    page.select_option("#curve-y", "end_effector.y")
    assert plot.locator("path.plot-series").count() == 3


def test_a_run_in_other_units_is_listed_and_not_drawn_and_runs_are_removed(page):
    choose(page, "job:sweep")
    page.fill("#option-outputs", "end_effector.x")
    run_job(page)
    keep_closing_curve(page)
    page.select_option("#model", "exact")
    run_job(page)  # the rerun in another model: this run and the kept one on the plot
    page.select_option("#curve-y", "end_effector.x")
    plot = page.locator("#curve svg.line-plot")
    legend = plot.locator(".plot-legend text").all_text_contents()
    assert len(legend) == 2 and legend[0].startswith("this run: sweep job, exact model")
    open_example(page, "gripper_si")  # newtons and metres
    choose(page, "job:sweep")
    page.fill("#option-outputs", "end_effector.x")
    run_job(page)
    page.click("#tab-curves")
    page.select_option("#curve-y", "end_effector.x")
    item = page.locator("#pinned-list li")
    assert item.count() == 1 and item.get_attribute("data-drawn") == "false"
    assert "not drawn: its actuation force y is in uN, the axis in N" in item.text_content()
    assert plot.locator("path.plot-series").count() == 1 and plot.locator(".plot-legend text").count() == 0
    screenshot(page, "compare-other-units")
    page.click("#pinned-list button")
    assert page.is_hidden("#compare")
    page.click("#pin-curve")
    page.click("#clear-pinned")
    assert page.is_hidden("#compare") and page.is_enabled("#pin-curve")


def test_the_arch_is_traced_along_a_path_picked_from_its_fields(page):
    open_example(page, "snap_through_arch")
    choose(page, "solve:trace")
    page.check("#option-trace")
    menu = "#option-trace-path-pick"
    labels = page.locator(f"{menu} option").all_text_contents()
    assert {"P force y (0)", "strip h (1)", "steel E (200)", "west length (50.09)"} <= set(labels), labels
    assert page.locator(f"{menu} optgroup").evaluate_all("gs => gs.map((g) => g.label)")[:2] == ["Loads", "Sections"]
    page.select_option(menu, label="P force y (0)")
    assert page.input_value("#option-trace-path") == "/loads/P/force/1"
    page.fill("#option-trace-stop", "-300")
    page.fill("#option-trace-step", "5")
    run_and_wait(page, "trace: converged", timeout=120_000)
    rows = page.locator("#panel-table table:has(caption:text('Limit points')) tbody tr")
    loads = [float(rows.nth(k).locator("td").first.get_attribute("title")) for k in range(rows.count())]
    core = trace_path(
        compile_mechanism(load_document(EXAMPLES / "snap_through_arch.json")), "/loads/P/force/1", -300, 5
    )
    assert len(loads) == 2 and loads == pytest.approx([lp.value for lp in core.limit_points], rel=1e-9)
    screenshot(page, "compare-arch-trace-picked")


def click_on_path(page, selector: str) -> None:
    """A click on the stroke of an SVG path or line (its middle), where a user points at it."""
    x, y = page.evaluate(
        """(selector) => { const path = document.querySelector(selector);
                           const p = path.getPointAtLength(path.getTotalLength() / 2);
                           const q = new DOMPoint(p.x, p.y).matrixTransform(path.getScreenCTM());
                           return [q.x, q.y]; }""",
        selector,
    )
    page.mouse.click(x, y)


def test_a_load_or_an_element_clicked_in_the_drawing_fills_the_path_field(page):
    choose(page, "job:sweep")
    field = "#option-parameters-0-path"
    page.fill(field, "")
    page.focus(field)
    click_on_path(page, '#drawing [data-load="actuation"] line')
    assert page.input_value(field) == "/loads/actuation/force/1"
    assert page.evaluate("document.activeElement.id") == field[1:]
    page.fill(field, "/sections/flexure/b")
    page.focus("#option-parameters-0-start")  # another field focused: a click in the drawing picks nothing
    click_on_path(page, '#drawing [data-load="actuation"] line')
    assert page.input_value(field) == "/sections/flexure/b"

    choose(page, "solve:equilibrium")  # a list of paths: a click adds to it
    page.check("#option-sensitivities")
    paths = "#option-sensitivities-parameters"
    page.fill(paths, "/materials/silicon/E")
    page.focus(paths)
    click_on_path(page, '#drawing [data-element="a"]')
    click_on_path(page, '#drawing [data-element="b"]')  # the same section: added once
    assert page.input_value(paths) == "/materials/silicon/E, /sections/flexure/h"
    page.select_option(f"{paths}-pick", "/loads/actuation/force/1")
    assert page.input_value(paths) == "/materials/silicon/E, /sections/flexure/h, /loads/actuation/force/1"
    screenshot(page, "compare-picked-in-drawing")
    page.fill("#option-sensitivities-outputs", "end_effector.x")
    run_and_wait(page, "equilibrium: converged")  # the service takes the fields picked
