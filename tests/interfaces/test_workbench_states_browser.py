# ruff: noqa: F811 (the fixtures imported from workbench are arguments of the tests)
"""The workbench's pictures true to the state they claim to show (issue 49), in a real Chromium
at 1400x900: a sweep's frames draw the swept load at each frame's value; a reloaded job shows
its own request's options and Run waits for its end; one progress figure per job; a refused run
says so where it was started; edits are not discarded without asking; the modes' animation
opens on mode 1; axes and curves carry the engineer's names (a load's name and component, the
frequency in Hz on a log axis); the export job shows a summary, not a manifest dump."""

from __future__ import annotations

import json
import math
import re

import pytest
from browser import screenshot
from conftest import EXAMPLES
from workbench import (  # noqa: F401 (fixtures by name)
    browser,
    choose,
    document_text,
    log,
    open_example,
    page,
    server,
    set_document_text,
)

from flexmech.service.display import number_text

FOLD = {"width": 1400, "height": 900}
DRAWN_LOADS = "() => Object.fromEntries([...document.querySelectorAll('#drawing g[data-load]')].map((g) => [g.dataset.load, g.textContent]))"
# Every visible text of the page that shows a whole percentage ("41 %"), with the id (or class)
# of its element; other jobs' entries in the recent jobs are theirs.
PERCENT_PLACES = r"""() => {
  const found = [];
  const job = location.pathname.split('/').pop();
  const walker = document.createTreeWalker(document.body, NodeFilter.SHOW_TEXT);
  while (walker.nextNode()) {
    const text = walker.currentNode, element = text.parentElement, entry = element.closest('#recent-list li');
    if (element.closest('[hidden]') || !element.getClientRects().length || (entry && entry.dataset.job !== job)) continue;
    if (/(^|[^\d.])\d{1,3} %/.test(text.textContent)) found.push(element.id || element.className || `${element.tagName}: ${text.textContent}`);
  }
  return found;
}"""


def start(page, example: str, choice: str | None = None) -> None:
    page.set_viewport_size(FOLD)
    page.evaluate("() => { document.body.dataset.offered = ''; }")
    open_example(page, example)
    page.wait_for_function("() => document.body.dataset.offered")
    if choice:
        choose(page, choice)


def wait_for_status(page, style: str, timeout: float = 180_000) -> None:
    page.wait_for_function(
        "s => document.getElementById('result-card').dataset.status === s", arg=style, timeout=timeout
    )


def sweep_gripper(page, steps: int) -> list[float]:
    """The gripper's actuation swept from -60 to 77 uN in `steps` (no until); its values."""
    start(page, "gripper", "job:sweep")
    page.uncheck("#option-until")
    page.fill("#option-parameters-0-start", "-60")
    page.fill("#option-parameters-0-stop", "77")
    page.fill("#option-parameters-0-steps", str(steps))
    page.fill("#option-outputs", "end_effector.x")
    page.click("#run")
    wait_for_status(page, "ok")
    page.wait_for_selector("#animation:not([hidden])")  # the path's states, drawn by the service
    return [point["values"][0] for point in json.loads(page.text_content("#raw"))["points"]]


def start_four_bar_job(page, until: float) -> str:
    """The four-bar's simulation job run to `until` s (minutes of work for 10 s); its id once
    it runs and has shown a partial result."""
    start(page, "four_bar_dynamics", "job:simulation")
    assert page.input_value("#option-simulate-until") == "1.5"  # the document's
    page.fill("#option-simulate-until", str(until))
    page.click("#run")
    page.wait_for_function("() => /^\\/jobs\\/[0-9a-f]{32}$/.test(location.pathname)")
    page.wait_for_function(
        "() => document.querySelector('#result-card[data-status=running] .headline')", timeout=120_000
    )
    return page.evaluate("() => location.pathname").split("/")[-1]


def cancel_and_wait(page) -> None:
    page.click("#cancel")
    wait_for_status(page, "cancelled", timeout=60_000)


def test_each_sweep_frame_draws_the_swept_load_at_that_frames_value(page):
    """The gripper's actuation is 50 uN in its document: each frame of the sweep draws it at the
    frame's own value (its size in the label, its sense by the arrow), not 50 uN upward."""
    values = sweep_gripper(page, 10)
    assert int(page.get_attribute("#frame", "max")) + 1 == len(values) == 11
    for k in (0, 5, 10):
        page.fill("#frame", str(k))
        page.dispatch_event("#frame", "input")
        label = page.text_content("#frame-label")
        shown = float(re.search(r" = ([-0-9.e]+) uN", label).group(1))
        assert shown == pytest.approx(values[k], rel=1e-4), label
        drawn = page.evaluate(DRAWN_LOADS)["actuation"]
        name, size, unit = drawn.split()
        assert (name, unit) == ("actuation", "uN") and float(size) == pytest.approx(abs(values[k]), rel=1e-3), (
            k,
            drawn,
        )
        line = page.locator('#drawing g[data-load="actuation"] line')
        tail, head = (float(line.get_attribute(end)) for end in ("y1", "y2"))
        assert (tail > head) == (values[k] > 0), (k, values[k], tail, head)  # SVG y runs down: upward is a smaller y
    screenshot(page, "states-sweep-last-frame")


def test_a_reloaded_job_shows_its_own_until_and_run_waits_for_its_end(page):
    job = start_four_bar_job(page, 7.5)
    assert page.is_disabled("#run")
    page.reload()
    page.wait_for_selector("body[data-ready=true]", state="attached", timeout=60_000)
    assert page.evaluate("() => location.pathname") == f"/jobs/{job}"
    assert page.input_value("#analysis") == "job:simulation"
    assert page.input_value("#option-simulate-until") == "7.5"  # the job's, not the document's 1.5
    assert page.get_attribute("#run", "aria-disabled") == "true" and page.is_disabled("#run")
    page.click("#run", force=True)  # refused by the page: no second job
    assert page.evaluate("() => location.pathname") == f"/jobs/{job}"
    assert page.get_attribute("#result-card", "data-status") == "running"
    screenshot(page, "states-reloaded-job")
    cancel_and_wait(page)
    page.wait_for_function("() => !document.getElementById('run').hasAttribute('aria-disabled')")
    assert page.is_enabled("#run")


def test_a_running_job_shows_its_progress_in_one_place(page):
    """Under Run, read at every poll; not again on the card (read at each partial result) nor
    in the recent jobs' entry of this page's job (read every 3 s), before and after a reload."""
    start_four_bar_job(page, 10)
    seen = []
    for _ in range(2):
        for _ in range(4):
            page.wait_for_timeout(400)
            seen.append(page.evaluate(PERCENT_PLACES))
        page.reload()
        page.wait_for_selector("body[data-ready=true]", state="attached", timeout=60_000)
        page.wait_for_function(
            "() => document.querySelector('#result-card[data-status=running] .headline')", timeout=60_000
        )
    assert page.locator("#recent-list a[aria-current=page]").count() == 1  # the job is listed, its figure not
    assert all(places == ["progress-text"] for places in seen), seen
    cancel_and_wait(page)


def test_a_refused_run_says_so_where_it_was_started(page, log):
    log.answered = (422,)
    start(page, "gripper", "job:sweep")
    page.fill("#option-parameters-0-path", "/loads/actuation/force/7")
    page.click("#run")
    page.wait_for_function("() => document.getElementById('run-state').dataset.style === 'failed'")
    said = page.text_content("#run-state")
    assert said.startswith("Refused: /parameters/0/path: not a numeric field"), said
    assert page.text_content("#result-status") == "refused"
    assert page.get_attribute("#result-card", "data-status") == "failed"
    outputs = page.text_content("#panel-table")
    assert "Running" not in outputs and outputs.startswith("Not run: the service refused"), outputs
    assert page.is_hidden("#job")  # no job, no progress
    assert not page.get_attribute("#run", "aria-disabled")  # a new run may start
    screenshot(page, "states-refused")


def test_edits_are_kept_unless_the_user_agrees_to_open_another_example(page):
    asked = []

    def refuse(dialog):
        asked.append(dialog.message)
        dialog.dismiss()

    page.on("dialog", refuse)
    start(page, "cantilever")  # nothing edited: no question
    start(page, "gripper")
    assert asked == []
    document = json.loads((EXAMPLES / "gripper.json").read_text())
    document["name"] = "my gripper"
    edited = json.dumps(document, indent=2)
    set_document_text(page, edited)
    page.wait_for_function("() => document.getElementById('mechanism-name').textContent === 'my gripper'")
    page.select_option("#example-select", "cantilever")
    page.click("#open-example")  # asked, and refused: the edits stay
    page.wait_for_function("() => document.getElementById('example-select').value === 'gripper'")
    assert len(asked) == 1 and "my gripper" in asked[0] and "discard" in asked[0], asked
    assert document_text(page) == edited and page.text_content("#mechanism-name") == "my gripper"
    page.remove_listener("dialog", refuse)
    page.once("dialog", lambda dialog: dialog.accept())
    page.select_option("#example-select", "cantilever")
    page.click("#open-example")  # asked, and agreed
    page.wait_for_function("() => document.getElementById('mechanism-name').textContent.startsWith('Large-deflection')")
    assert json.loads(document_text(page))["name"].startswith("Large-deflection")


def test_the_mode_animation_opens_on_mode_1(page):
    start(page, "gripper_modes", "solve:modes")
    page.click("#run")
    wait_for_status(page, "ok")
    modes = len(json.loads(page.text_content("#raw"))["modes"])
    assert modes == 6
    assert page.input_value("#frame") == "0" and int(page.get_attribute("#frame", "max")) + 1 == 24 * modes
    assert page.text_content("#frame-label").startswith(f"1 / {24 * modes}: mode 1: 2200 Hz")
    assert page.text_content("#drawing .frame-label") == "mode 1: 2200 Hz"
    screenshot(page, "states-modes-open")


def test_axes_and_curves_are_named_as_an_engineer_reads_them(page):
    """A swept load by its name and component; the frequency in Hz on a log axis (each point
    where its log10 puts it between the decades' ticks), no log10 series."""
    sweep_gripper(page, 4)
    page.click("#tab-curves")
    options = page.evaluate("() => [...document.querySelectorAll('#curve-x option')].map((o) => o.text)")
    assert options == ["actuation force y [uN]", "end_effector.x [mm]"]
    assert page.text_content("#curve .plot-x-label") == "actuation force y [uN]"
    heads = page.locator("#panel-table thead th").all_text_contents()
    assert "actuation force y [uN]" in heads and not [h for h in heads if h.startswith("/")]
    assert page.text_content("#frame-label").endswith("actuation force y = 77 uN")
    start(page, "gripper_modes", "solve:frequency_response")
    page.fill("#option-input", "/loads/actuation/force/1")
    page.fill("#option-outputs", "end_effector.x")
    page.fill("#option-points", "200")
    page.click("#run")
    wait_for_status(page, "ok")
    page.click("#tab-curves")
    options = page.evaluate("() => [...document.querySelectorAll('#curve-x option')].map((o) => o.text)")
    assert "frequency [Hz]" in options and not [o for o in options if "log10" in o]
    plot = page.locator("#curve svg")
    assert plot.get_attribute("data-x-scale") == "log" and page.text_content("#curve .plot-x-label") == "frequency [Hz]"
    ticks = {t.text_content(): t for t in plot.locator(".plot-x-tick").all()}
    assert {"1000", "10000"} <= set(ticks), list(ticks)
    left, right = (float(ticks[v].get_attribute("x")) for v in ("1000", "10000"))
    frequencies = json.loads(page.text_content("#raw"))["frequencies"]
    drawn = [float(x) for x in re.findall(r"[ML]([0-9.]+),", plot.locator("path.plot-series").get_attribute("d"))]
    assert len(drawn) == len(frequencies)  # one vertex per frequency: each where its log10 puts it
    where = [left + (right - left) * (math.log10(f) - 3) for f in frequencies]
    assert max(abs(x - w) for x, w in zip(drawn, where)) < 0.2  # 0.1 px: the path's rounding
    screenshot(page, "states-frequency-log-axis")


def test_an_export_job_shows_its_summary(page):
    start(page, "gripper", "job:export")
    page.click("#run")
    wait_for_status(page, "ok")
    result = json.loads(page.text_content("#raw"))
    manifest, archive = result["manifest"], result["archive"]
    tables = {t.locator("caption").text_content().split(" (")[0]: t for t in page.locator("#panel-table table").all()}
    assert set(tables) == {"Functions", "Inputs", "Outputs"}
    functions = tables["Functions"]
    names = functions.locator("tbody th").all_text_contents()
    assert names == [f"{manifest['name']}_{task}" for task in ("equilibrium", "stiffness", "target")]
    assert "time per call: not measured here" in functions.locator("caption").text_content()
    steps = functions.locator("tbody tr").first.locator("td").last.text_content()
    worst = manifest["worst_case_iterations"]
    assert steps == f"{worst['equilibrium_warm']} from the last solution, {worst['equilibrium_cold']} from rest"
    inputs = [r.locator("th, td").all_text_contents() for r in tables["Inputs"].locator("tbody tr").all()]
    assert [(r[0], r[1], r[-1]) for r in inputs] == [
        ("actuation_force_x", "actuation force x (/loads/actuation/force/0)", "uN"),
        ("actuation_force_y", "actuation force y (/loads/actuation/force/1)", "uN"),
    ]
    outputs = {
        r.locator("th").text_content(): r.locator("td").last.text_content()
        for r in tables["Outputs"].locator("tbody tr").all()
    }
    assert outputs == {o["name"]: o["unit"] for o in manifest["outputs"]} and outputs["anchor_m"] == "uN*mm"
    assert "?" not in page.text_content("#panel-table")
    assert page.text_content("#result-card .headline-item:first-child").startswith(
        f"archive{number_text(archive['bytes'] / 1000)} kB"  # six digits, as every number (service.display)
    )
    screenshot(page, "states-export-summary")
