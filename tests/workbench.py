"""The workbench in a real Chromium against a live uvicorn with API keys on: the fixtures
(`server`, `browser`, `log`, `page`) and the steps a user takes (open an example, choose an
analysis, run it), shared by the browser test modules. A module that wants them imports the
fixtures by name (`from workbench import server, browser, log, page`)."""

from __future__ import annotations

import json
from urllib.parse import urlsplit

import pytest
from browser import CHROMIUM_FLAGS, PageLog, chromium_path
from conftest import EXAMPLES, sqlite_server

KEY = "workbench-test-key"


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    server = sqlite_server(tmp_path_factory, "workbench", keys=(KEY,), FLEXMECH_CHUNK_SIZE="2")
    yield server
    server.stop()


@pytest.fixture(scope="module")
def browser():
    from playwright.sync_api import sync_playwright

    with sync_playwright() as playwright:
        chromium = playwright.chromium.launch(executable_path=chromium_path(), headless=True, args=CHROMIUM_FLAGS)
        yield chromium
        chromium.close()


@pytest.fixture
def log():
    return PageLog()


@pytest.fixture
def page(browser, server, log):
    """A page of the workbench with the API key given (as a user types it once)."""
    context = browser.new_context(viewport={"width": 1280, "height": 800})
    context.add_init_script(f"localStorage.setItem('flexmech.apiKey', {json.dumps(KEY)})")
    page = context.new_page()
    log.watch(page)
    page.goto(server.url + "/")
    page.wait_for_selector("body[data-ready=true]", state="attached", timeout=60_000)
    yield page
    assert_local_and_quiet(log, server)
    context.close()


def assert_local_and_quiet(log: PageLog, server) -> None:
    """Every request went to the server on loopback (blob: and data: URLs are made in the
    page), and the page logged no error or warning."""
    origin = urlsplit(server.url).netloc
    away = [url for url in log.requests if not url.startswith(("blob:", "data:")) and urlsplit(url).netloc != origin]
    assert log.requests and not away, f"requests that left the machine: {away}"
    assert not log.problems(log.answered), log.problems(log.answered)


def choose(page, analysis: str) -> None:
    page.select_option("#analysis", analysis)


def run_and_wait(page, text: str, timeout: float = 120_000) -> None:
    page.click("#run")
    page.wait_for_function(
        "t => document.getElementById('run-state').textContent.includes(t)", arg=text, timeout=timeout
    )


def open_example(page, name: str) -> None:
    """Open an example from the menu; wait until it is drawn under its own name."""
    title = json.loads((EXAMPLES / f"{name}.json").read_text())["name"]
    page.select_option("#example-select", name)
    page.click("#open-example")
    page.wait_for_function("t => document.getElementById('mechanism-name').textContent === t", arg=title)


def simulate_to_the_first_frame(page, example: str, until: float) -> None:
    """Run the simulate analysis of an example until `until` s; the slider at its first frame."""
    open_example(page, example)
    choose(page, "solve:simulate")
    page.check("#option-simulate")
    page.fill("#option-simulate-until", str(until))
    run_and_wait(page, "simulate: finished", timeout=180_000)
    page.locator("#frame").focus()
    page.keyboard.press("Home")


def set_document_text(page, text: str) -> None:
    """Replace the editor's text as a user pastes it: all selected, then the text typed in one
    go (the page hears "input" and redraws)."""
    page.click("#editor")
    page.keyboard.press("Control+A")
    page.keyboard.insert_text(text)
    assert document_text(page) == text


def document_text(page) -> str:
    """The editor's whole text (as the page reads it)."""
    return page.evaluate("async () => (await import('/workbench/editor.js')).text()")


def selected_text(page) -> str:
    """The text selected in the editor."""
    return page.evaluate("() => getSelection().toString()")
