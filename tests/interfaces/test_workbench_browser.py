# ruff: noqa: F811 (the fixtures imported from workbench are arguments of the tests)
"""The workbench page end to end: Debian's Chromium, driven by Playwright, against a live
uvicorn with API keys on. Each test writes screenshots of its states to out/workbench/; no
request of the page may leave the machine, and no page may log an error or a warning."""

from __future__ import annotations

import io
import json
import re

import ezdxf
import pytest
from browser import screenshot
from conftest import ACTUATION, EXAMPLES
from workbench import (  # noqa: F401 (fixtures by name)
    KEY,
    assert_local_and_quiet,
    browser,
    choose,
    document_text,
    log,
    open_example,
    page,
    run_and_wait,
    selected_text,
    server,
    set_document_text,
    simulate_to_the_first_frame,
)

from flexmech.models import compile_mechanism, load_document
from flexmech.service import solve_for_target
from flexmech.service.solvers.continuation import trace_path


@pytest.fixture(scope="module")
def closing_force() -> float:
    """The gripper's closing force by the core, for the page to show (77.03 uN)."""
    mech = compile_mechanism(load_document(EXAMPLES / "gripper.json"))
    return solve_for_target(mech, ACTUATION, "end_effector.x", 0.0).value


def element_path(page, name: str) -> str:
    return page.get_attribute(f'#drawing [data-element="{name}"]', "d")


def test_the_page_asks_for_the_key_then_paints_the_gripper_within_a_second(browser, server, log, capsys):
    log.answered = (401,)  # the first visit, without the key
    context = browser.new_context(viewport={"width": 1280, "height": 800})
    page = context.new_page()
    log.watch(page)
    page.goto(server.url + "/")
    page.wait_for_selector("body[data-ready=true]", state="attached", timeout=60_000)
    assert "missing API key" in page.text_content("#run-state")
    screenshot(page, "01-api-key-asked")
    page.fill("#api-key", KEY)
    page.press("#api-key", "Enter")
    page.wait_for_selector('#drawing [data-element="d"]', timeout=60_000)
    first = page.evaluate("performance.getEntriesByName('flexmech-drawn')[0].startTime")
    page.reload()  # the key is kept; the server has the gripper's graphs now
    page.wait_for_selector('#drawing [data-element="d"]', timeout=60_000)
    paint = page.evaluate("performance.getEntriesByName('first-contentful-paint')[0].startTime")
    drawn = page.evaluate("performance.getEntriesByName('flexmech-drawn')[0].startTime")
    with capsys.disabled():  # printed in every run, not only when the test fails
        print(
            f"\nworkbench on loopback: first contentful paint {paint:.0f} ms, gripper drawn {drawn:.0f} ms "
            f"(the first visit drew it {first:.0f} ms after opening, the key typed and the graphs built)"
        )
    assert paint < 1000 and drawn < 1000
    assert page.get_attribute("#drawing svg", "aria-label").endswith("drawn to scale in mm")
    assert {"x [mm]", "y [mm]"} <= set(page.locator("#drawing .axis-label").all_text_contents())
    assert page.locator("#drawing [data-body]").count() == 4 and page.locator("#drawing .arrow").count() == 1
    screenshot(page, "02-gripper-drawn")
    assert_local_and_quiet(log, server)
    context.close()


def test_the_gripper_closing_force_is_read_from_the_page(page, closing_force):
    choose(page, "solve:equilibrium")
    assert page.is_checked("#option-target")  # from the document's sweep: until end_effector.x = 0
    assert page.input_value("#option-target-path") == "/loads/actuation/force/1"
    run_and_wait(page, "equilibrium: converged")
    shown = page.text_content("#target-value")
    assert shown.startswith("77.03") and float(shown) == pytest.approx(closing_force, abs=1e-3)
    assert "uN" in page.text_content("#target")
    page.wait_for_function("() => document.getElementById('drawing-caption').textContent.startsWith('Deformed')")
    undeformed = json.loads(
        page.evaluate("JSON.stringify(document.querySelector('#drawing [data-element=a]').getAttribute('d'))")
    )
    assert undeformed  # the deformed centre line is drawn over the dashed undeformed one
    row = page.locator('#panel-table tr[data-name="end_effector.x"] td').all_text_contents()
    assert abs(float(row[0])) < 1e-6 and row[1] == "mm"  # closed: the end effector at x = 0
    screenshot(page, "03-gripper-closing-force")


def test_the_sweep_job_runs_until_the_gripper_closes(page, closing_force):
    """The form comes from the sweep request's schema, its `until` from the document's sweep
    section (as `flexmech sweep` reads it): the load path ends at the closing force."""
    choose(page, "job:sweep")
    assert page.is_checked("#option-until")
    assert page.input_value("#option-until-output") == "end_effector.x"
    assert page.input_value("#option-parameters-0-start") == "-60"
    assert page.input_value("#option-parameters-0-stop") == ""  # until finds it
    page.fill("#option-outputs", "end_effector.x")
    run_and_wait(page, "job succeeded", timeout=180_000)
    result = json.loads(page.text_content("#raw"))
    assert result["until"]["value"] == pytest.approx(closing_force, rel=1e-9)
    last = result["points"][-1]
    assert len(result["points"]) == 101 and last["values"][0] == pytest.approx(closing_force, rel=1e-9)
    assert abs(last["outputs"]["end_effector.x"]) < 1e-9
    screenshot(page, "04-sweep-until-closed")


def test_a_sweep_shows_its_progress_up_to_100_percent_and_its_curve_with_hover(page):
    choose(page, "job:sweep")
    page.uncheck("#option-until")  # the document's sweep runs until closure: here a fixed range
    page.fill("#option-parameters-0-start", "0")
    page.fill("#option-parameters-0-stop", "80")
    page.fill("#option-parameters-0-steps", "600")  # a load path in order, two points per task: seconds of work
    page.fill("#option-outputs", "end_effector.x, end_effector.y")
    page.evaluate("""() => {
        window.progressSeen = [];
        window.pointsWhileRunning = 0;  // rows of the points table shown before the job ended
        new MutationObserver(() => {
            const value = document.getElementById('progress').value;
            window.progressSeen.push(value);
            if (value < 100) window.pointsWhileRunning = Math.max(window.pointsWhileRunning,
                document.querySelectorAll('#panel-table tbody tr').length);
        }).observe(document.getElementById('progress-text'), {childList: true, characterData: true, subtree: true});
    }""")
    page.click("#run")
    page.wait_for_function(
        "() => document.getElementById('progress-text').textContent.includes('running')", timeout=60_000
    )
    screenshot(page, "04-sweep-running")
    page.wait_for_function(
        "() => document.getElementById('progress-text').textContent.includes('succeeded: 100 %')", timeout=120_000
    )
    assert "(601 of 601)" in page.text_content("#progress-text")
    assert page.get_attribute("#progress", "value") == "100"
    seen = page.evaluate("window.progressSeen")
    assert seen == sorted(seen) and seen[-1] == 100 and any(0 < value < 100 for value in seen), seen
    assert 0 < page.evaluate("window.pointsWhileRunning") < 601  # points shown as they came
    page.wait_for_function("() => document.getElementById('run-state').textContent.includes('job succeeded')")
    # the last points arrive with the finished result, a moment after the bar reads 100 %
    page.wait_for_function("() => document.querySelectorAll('#panel-table tbody tr').length === 500", timeout=10_000)
    page.wait_for_selector("#animation:not([hidden])")  # the load path's states, drawn by the service
    page.locator("#frame").focus()
    page.keyboard.press("Home")
    body = '#drawing [data-body="input"]'
    at_rest = float(page.get_attribute(body, "cy"))
    assert "= 0 uN" in page.text_content("#frame-label")
    page.keyboard.press("End")
    assert "= 80 uN" in page.text_content("#frame-label")
    assert float(page.get_attribute(body, "cy")) < at_rest - 5  # pushed up by 80 uN (SVG y runs down)
    page.click("#tab-curves")
    assert page.input_value("#curve-x") == "/loads/actuation/force/1"
    plot = page.locator("#curve svg")
    plot.scroll_into_view_if_needed()
    box = plot.bounding_box()
    page.mouse.move(box["x"] + box["width"] * 0.55, box["y"] + box["height"] * 0.5)
    tooltip = page.locator("#curve .plot-tooltip").all_text_contents()
    assert any(re.search(r"x = [0-9]", text) for text in tooltip), tooltip
    screenshot(page, "05-sweep-curve-hover")


def test_an_unknown_body_is_shown_at_its_pointer(page, log):
    log.answered = (422,)
    document = json.loads((EXAMPLES / "gripper.json").read_text())
    document["elements"]["c"]["to"] = "folower"
    set_document_text(page, json.dumps(document, indent=2))
    page.click("#draw")
    problem = page.locator('#problems li[data-pointer="/elements/c/to"]')
    problem.wait_for(timeout=30_000)
    assert "unknown body 'folower'" in problem.text_content()
    problem.locator("button").click()  # selects the field in the text
    assert selected_text(page) == '"folower"'
    screenshot(page, "06-unknown-body")


def test_a_contact_path_runs_as_a_job_and_its_animation_steps(page):
    open_example(page, "gripper_jaw_contact")
    choose(page, "job:contact_path")
    assert page.is_checked("#option-path")  # from the document's contacts.path
    assert page.input_value("#option-path-0-path") == "/contacts/objects/fixture/centre/0"
    page.fill("#option-path-0-start", "80")
    page.fill("#option-path-0-stop", "60")
    page.fill("#option-path-0-steps", "8")
    run_and_wait(page, "job succeeded", timeout=180_000)
    assert page.get_attribute("#frame", "max") == "8"
    slider = page.locator("#frame")
    slider.focus()
    page.keyboard.press("Home")
    first = page.text_content("#frame-label")
    fixture_first = page.get_attribute("#drawing svg g path[fill='#f6e3cc']", "d")
    screenshot(page, "07-contact-path-first-state")
    for _ in range(5):
        page.keyboard.press("ArrowRight")
    assert page.text_content("#frame-label").startswith("6 / 9") and page.text_content("#frame-label") != first
    assert "= 67.5 mm" in page.text_content("#frame-label")  # 80 - 5 x 2.5 mm
    assert page.get_attribute("#drawing svg g path[fill='#f6e3cc']", "d") != fixture_first  # the fixture moved
    assert page.locator("#drawing .arrow").count() >= 1  # the contact force
    screenshot(page, "08-contact-path-state-6")


def test_a_simulation_animates_the_links_and_plots_its_energies(page):
    simulate_to_the_first_frame(page, "slider_crank_dynamics", 0.6)
    assert int(page.get_attribute("#frame", "max")) + 1 > 10
    assert "t = 0 s" in page.text_content("#frame-label")
    rod_at_start = element_path(page, "rod")
    page.keyboard.press("End")
    assert "t = 0.6 s" in page.text_content("#frame-label")
    assert element_path(page, "rod") != rod_at_start  # the crank has turned the rod
    screenshot(page, "09-simulation-last-frame")
    page.click("#play")
    page.wait_for_function("() => document.getElementById('play').textContent === 'Play'", timeout=30_000)
    page.click("#tab-energies")
    legend = page.locator("#energy-plot svg text").all_text_contents()
    assert {"kinetic", "input_work"} <= set(legend)
    screenshot(page, "10-simulation-energies")


def test_an_impact_simulation_moves_the_body_inside_its_clearance(page):
    simulate_to_the_first_frame(page, "csfh_central_impact", 0.2)
    pin = "#drawing [data-outline=pin]"
    start = page.get_attribute(pin, "d")
    page.keyboard.press("PageUp")  # a tenth of the way on
    page.keyboard.press("PageUp")
    assert page.get_attribute(pin, "d") != start  # the pin falls
    page.click("#tab-curves")
    page.select_option("#curve-y", "hinge.y")
    assert page.locator("#curve svg path").count() > 0
    screenshot(page, "11-impact-simulation")


def test_a_running_job_is_cancelled_from_the_page(page):
    open_example(page, "four_bar_dynamics")
    choose(page, "job:simulation")
    page.fill("#option-simulate-until", "30")  # minutes of work
    page.uncheck("#option-simulate-shapes")
    page.click("#run")
    page.wait_for_function(
        "() => document.getElementById('progress-text').textContent.includes('running')", timeout=60_000
    )
    screenshot(page, "12-job-running")
    page.click("#cancel")
    page.wait_for_function(
        "() => document.getElementById('progress-text').textContent.includes('cancelled')", timeout=60_000
    )
    assert page.is_disabled("#cancel")
    page.wait_for_function("() => document.getElementById('run-state').textContent.includes('job cancelled')")
    job_page = page.get_attribute("#job-link", "href")
    assert re.fullmatch(r"/jobs/[0-9a-f]{32}", job_page)
    screenshot(page, "13-job-cancelled")
    assert page.evaluate("() => location.pathname") == job_page  # the address bar has had it since the run
    page.goto(page.url.split("/jobs/")[0] + job_page)  # the job's own page, for a design tool to link to
    page.wait_for_function(
        "() => document.getElementById('progress-text').textContent.includes('cancelled')", timeout=60_000
    )
    assert "four-bar" in page.text_content("#mechanism-name")
    screenshot(page, "14-job-page")


def test_the_page_fits_a_narrow_window_and_is_reached_by_keyboard(page):
    page.set_viewport_size({"width": 390, "height": 800})
    assert page.evaluate("document.scrollingElement.scrollWidth <= window.innerWidth + 1")
    page.focus("#api-key")
    reached = []
    for _ in range(40):
        page.keyboard.press("Tab")
        reached.append(page.evaluate("document.activeElement.id"))
        if reached[-1] == "run":
            break
    assert "example-select" in reached and "editor" in reached and reached[-1] == "run"
    page.keyboard.press("Enter")  # runs the equilibrium from the keyboard
    page.wait_for_function(
        "() => document.getElementById('run-state').textContent.includes('converged')", timeout=60_000
    )
    unnamed = page.evaluate("""() => [...document.querySelectorAll('button, input, select, textarea, [tabindex]')]
        .filter((e) => !(e.labels && e.labels.length) && !e.getAttribute('aria-label') && !e.textContent.trim()
                       && !e.closest('label') && !e.hasAttribute('hidden'))
        .map((e) => e.outerHTML.slice(0, 80))""")
    assert not unnamed, unnamed  # every control has a name a screen reader can say
    screenshot(page, "15-narrow-window")


def test_a_trace_passes_the_arch_limit_points(page):
    open_example(page, "snap_through_arch")
    choose(page, "solve:trace")
    page.check("#option-trace")
    page.fill("#option-trace-path", "/loads/P/force/1")
    page.fill("#option-trace-stop", "-300")
    page.fill("#option-trace-step", "5")
    run_and_wait(page, "trace: converged", timeout=120_000)
    rows = page.locator("#panel-table table:has(caption:text('Limit points')) tbody tr")
    assert rows.count() == 2
    kinds = [rows.nth(k).locator("th").text_content() for k in range(2)]
    loads = [float(rows.nth(k).locator("td").first.get_attribute("title")) for k in range(2)]
    core = trace_path(
        compile_mechanism(load_document(EXAMPLES / "snap_through_arch.json")), "/loads/P/force/1", -300, 5
    )
    assert kinds == [lp.kind for lp in core.limit_points]
    assert loads == pytest.approx([lp.value for lp in core.limit_points], rel=1e-9)
    page.click("#tab-curves")
    assert page.input_value("#curve-y") == "/loads/P/force/1"
    page.locator("#frame").focus()
    page.keyboard.press("Home")
    crown = '#drawing [data-body="crown"]'
    at_rest = float(page.get_attribute(crown, "cy"))
    page.keyboard.press("End")  # past both limit points: the arch has snapped through
    assert "= -300 N" in page.text_content("#frame-label")
    assert float(page.get_attribute(crown, "cy")) > at_rest + 20  # the crown is drawn lower (SVG y runs down)
    screenshot(page, "16-trace-arch")


def test_an_optimization_shows_its_design_and_draws_the_optimum(page):
    open_example(page, "gripper_sections")
    choose(page, "job:optimization")
    run_and_wait(page, "job succeeded", timeout=180_000)
    row = page.locator('#panel-table tr[data-name="/sections/flexure/h"] td')
    start, optimum = (float(row.nth(k).get_attribute("title")) for k in (0, 1))
    assert start == pytest.approx(0.005) and optimum > start  # thicker flexures than the start
    page.wait_for_function("() => document.getElementById('drawing-caption').textContent.startsWith('Deformed')")
    with page.expect_download() as info:  # the DXF for the shop draws the optimum, not the start
        page.click("#download-dxf")
    space = ezdxf.read(io.StringIO(info.value.path().read_text())).modelspace()
    radii = {round(v.dxf.radius, 9) for e in space for v in e.virtual_entities() if v.dxftype() == "ARC"}
    assert sorted(radii) == pytest.approx([0.2 - optimum / 2, 0.2 + optimum / 2], abs=1e-9)
    screenshot(page, "17-optimization")


def test_a_yaml_upload_is_drawn_and_downloads_are_made(page, tmp_path, closing_force):
    import yaml

    document = json.loads((EXAMPLES / "gripper.json").read_text())
    path = tmp_path / "my_gripper.yaml"
    document["name"] = "uploaded gripper"
    path.write_text(yaml.safe_dump(document, sort_keys=False))
    page.set_input_files("#upload", str(path))
    page.wait_for_function("() => document.getElementById('mechanism-name').textContent === 'uploaded gripper'")
    assert document_text(page).startswith("schema_version: 1")
    run_and_wait(page, "equilibrium: converged")
    downloads, names = {}, {}
    for kind in ("json", "csv", "svg", "png", "dxf", "gds"):
        with page.expect_download() as info:
            page.click(f"#download-{kind}")
        downloads[kind], names[kind] = info.value.path().read_bytes(), info.value.suggested_filename
    answer = json.loads(downloads["json"])
    assert answer["target"]["value"] == pytest.approx(closing_force, rel=1e-9)
    assert downloads["csv"].startswith(b"output,value,unit\n")
    assert b"<svg" in downloads["svg"] and b"x [mm]" in downloads["svg"]
    assert downloads["png"].startswith(b"\x89PNG")
    # the fabricated outlines, made by the service: DXF text with its layers, a GDSII HEADER record
    assert (
        names["dxf"] == "uploaded_gripper.dxf" and b"LWPOLYLINE" in downloads["dxf"] and b"flexures" in downloads["dxf"]
    )
    assert names["gds"] == "uploaded_gripper.gds" and downloads["gds"][:4] == b"\x00\x06\x00\x02"
    screenshot(page, "18-yaml-upload")


def test_a_contact_solve_draws_the_state_and_tables_the_pair(page):
    open_example(page, "gripper_jaw_contact")
    choose(page, "solve:contact")
    page.click("#run-panel details summary")  # more request fields: the fixture moved in
    page.fill("#extra", json.dumps({"overrides": {"/contacts/objects/fixture/centre/0": 67.81}}))
    run_and_wait(page, "contact: converged", timeout=120_000)
    cells = page.locator('#panel-table tr[data-name="insertion"] td').all_text_contents()
    assert cells[0] in ("frictionless", "slipping", "sticking") and float(cells[1]) > 0  # touching, pressed
    assert page.locator("#drawing .arrow").count() == 1  # the contact force at its point
    assert page.text_content("#drawing-caption").startswith("The state found")
    screenshot(page, "19-contact-solve")


def test_a_bad_option_is_marked_at_its_field(page, log):
    log.answered = (422,)
    choose(page, "job:sweep")
    page.fill("#option-parameters-0-path", "/loads/actuation/force/7")
    page.click("#run")
    problem = page.locator('#problems li[data-pointer="/parameters/0/path"]')
    problem.wait_for(timeout=30_000)
    assert "not a numeric field of this mechanism" in problem.text_content()
    assert page.get_attribute("#option-parameters-0-path", "aria-invalid") == "true"
    assert page.evaluate("document.activeElement.id") == "option-parameters-0-path"
    screenshot(page, "20-bad-option")


def test_the_modes_are_tabled_and_each_swings_in_the_drawing(page):
    open_example(page, "rod_free_vibration")
    choose(page, "solve:modes")
    page.fill("#option-count", "3")
    page.select_option("#option-at", "undeformed")
    run_and_wait(page, "modes: converged")
    table = page.locator("#panel-table table", has_text="Natural modes")
    row = table.locator("tbody tr").first
    cells = row.locator("td").all_text_contents()
    assert row.locator("th").text_content() == "1" and cells[0] == "elastic"
    assert float(cells[1]) == pytest.approx(2.11769, rel=1e-3)  # Hz: 1 / 0.47221 s, as the table rounds it
    assert int(page.get_attribute("#frame", "max")) + 1 == 3 * 24  # one period of each mode
    page.locator("#frame").focus()
    page.keyboard.press("Home")
    assert "mode 1: 2.1177 Hz" in page.text_content("#frame-label")
    at_rest = element_path(page, "rod")
    for _ in range(6):
        page.keyboard.press("ArrowRight")  # a quarter period: the largest swing
    assert element_path(page, "rod") != at_rest
    table.locator('tbody tr[data-name="2"]').click()  # a mode picked from the table plays alone
    assert int(page.get_attribute("#frame", "max")) + 1 == 24
    page.wait_for_function("() => document.getElementById('play').textContent === 'Play'", timeout=30_000)
    assert "mode 2: 13.271 Hz" in page.text_content("#frame-label")
    screenshot(page, "21-modes")


def test_a_frequency_response_plots_its_amplitude_in_db_and_tables_its_resonances(page):
    open_example(page, "gripper_modes")
    choose(page, "solve:frequency_response")
    page.fill("#option-input", "/loads/actuation/force/1")
    page.fill("#option-outputs", "end_effector.x")
    page.fill("#option-points", "300")
    run_and_wait(page, "frequency_response: converged")
    assert page.input_value("#curve-x") == "frequency" and page.input_value("#curve-y") == "end_effector.x dB"
    resonances = page.locator("#panel-table table", has_text="Resonances").locator("tbody tr")
    assert resonances.count() >= 5
    first = float(resonances.first.locator("td").nth(1).text_content())  # after mode (th) and output
    heads = page.locator("#panel-table table", has_text="Resonances").locator("thead th").all_text_contents()
    frequency_head = next(head for head in heads if head.startswith("frequency"))
    per_hertz = {"frequency [Hz]": 1.0, "frequency [kHz]": 1e3}[frequency_head]  # its display unit (display.js)
    assert first * per_hertz == pytest.approx(2200.0, rel=1e-3)  # the first mode (about 2200 Hz), its damped peak
    page.click("#tab-curves")
    assert page.locator("#curve svg path").count() >= 1
    screenshot(page, "22-frequency-response")


def test_an_export_job_offers_its_c_library_for_download(page):
    """The export job (issue 29) from the page: when it succeeds the card offers the archive,
    fetched with the key; it holds the library's header and manifest with the closing force's
    sweep."""
    import io
    import tarfile

    assert page.is_hidden("#download-archive")
    choose(page, "job:export")
    run_and_wait(page, "job succeeded", timeout=120_000)
    page.wait_for_selector("#download-archive", state="visible")
    with page.expect_download() as info:
        page.click("#download-archive")
    assert info.value.suggested_filename.endswith(".tar.gz")
    with tarfile.open(fileobj=io.BytesIO(info.value.path().read_bytes()), mode="r:gz") as tar:
        names = tar.getnames()
        manifest = json.loads(tar.extractfile(next(n for n in names if n.endswith("manifest.json"))).read())
    assert any(n.endswith(".h") for n in names) and any(n.endswith("_kernels.c") for n in names)
    assert manifest["target"]["output"] == "end_effector.x"
    assert [i["name"] for i in manifest["inputs"]] == ["actuation_force_x", "actuation_force_y"]
