# ruff: noqa: F811 (the fixtures imported from workbench are arguments of the tests)
"""The workbench's document editor (CodeMirror, api/web/editor.js) in Chromium: line numbers,
every problem of a document marked at its line with its message and listed under it, a JSON
syntax error marked with a "show" button, field names completed from the document's schema,
YAML highlighted and edited. Screenshots go to out/workbench/ (editor-*)."""

from __future__ import annotations

import json
import re

import yaml
from browser import screenshot
from conftest import EXAMPLES
from workbench import (  # noqa: F401 (fixtures by name)
    browser,
    document_text,
    log,
    open_example,
    page,
    server,
    set_document_text,
)


def gripper() -> dict:
    return json.loads((EXAMPLES / "gripper.json").read_text())


def line_of(text: str, snippet: str) -> int:
    """The line number (from 1) of the one line of `text` that holds `snippet`."""
    found = [n for n, line in enumerate(text.splitlines(), start=1) if snippet in line]
    assert len(found) == 1, (snippet, found)
    return found[0]


def marked(page) -> list[dict]:
    """The problems marked in the editor: [{line, message}]."""
    return page.evaluate("async () => (await import('/workbench/editor.js')).markedProblems()")


# CodeMirror's completion ignores Enter in its first 75 ms (interactionDelay), so that a key
# pressed as the list opens types what it always typed; a person waits longer than that.
ACCEPT_AFTER_MS = 250


def select_field(page, pointer: str) -> None:
    """Select a field's text in the editor, as its problem's "show" button does."""
    assert page.evaluate("async (p) => (await import('/workbench/editor.js')).select(p)", pointer)


def active_line_number(page) -> str:
    return page.text_content(".cm-activeLineGutter").strip()


def test_three_problems_are_marked_at_their_lines_and_listed(page, log):
    log.answered = (422,)
    document = gripper()
    document["bodies"]["input"]["position"] = "here"
    document["elements"]["a"]["radius"] = True
    document["loads"]["actuation"]["colour"] = "red"
    text = json.dumps(document, indent=2)
    lines = {
        "/bodies/input/position": line_of(text, '"position": "here"'),
        "/elements/a/radius": line_of(text, '"radius": true'),
        "/loads/actuation/colour": line_of(text, '"colour": "red"'),
    }
    set_document_text(page, text)
    page.click("#draw")
    page.wait_for_function("() => document.querySelectorAll('#problems li').length === 3", timeout=30_000)
    items = page.locator("#problems li")
    assert sorted(items.nth(k).get_attribute("data-pointer") for k in range(3)) == sorted(lines)
    problems = marked(page)
    assert sorted(p["line"] for p in problems) == sorted(lines.values())
    by_line = {p["line"]: p["message"] for p in problems}
    assert by_line[lines["/loads/actuation/colour"]] == "unknown field 'colour'"
    assert by_line[lines["/bodies/input/position"]] == "Input should be a valid tuple"
    assert by_line[lines["/elements/a/radius"]].startswith("expected a number")
    for pointer, line in lines.items():  # each "show" goes to its line, marked there with its message
        page.click(f'#problems li[data-pointer="{pointer}"] button')
        assert active_line_number(page) == str(line)
        active = page.locator(".cm-activeLine")
        assert active.locator(".cm-lintRange-error").count() == 1
        assert active.locator(".cm-problem-note").text_content().strip() == by_line[line]
    assert page.locator(".cm-lint-marker-error").count() >= 1  # in the gutter, beside the line numbers
    page.set_viewport_size({"width": 1400, "height": 900})
    screenshot(page, "editor-01-three-problems")
    page.set_viewport_size({"width": 390, "height": 800})
    page.locator("#problems").scroll_into_view_if_needed()
    screenshot(page, "editor-02-three-problems-phone")
    assert page.evaluate("document.scrollingElement.scrollWidth <= window.innerWidth + 1")


def test_a_json_syntax_error_is_marked_and_shown(page):
    text = json.dumps(gripper(), indent=2)
    broken = text.replace('"schema_version": 1,', '"schema_version": 1', 1)  # a comma missing
    set_document_text(page, broken)
    page.click("#draw")
    problem = page.locator('#problems li[data-pointer=""]')
    problem.wait_for(timeout=30_000)
    assert "not valid JSON" in problem.text_content()
    stop = line_of(broken, '"name": ')  # JSON.parse stops at the next key
    assert [p["line"] for p in marked(page)] == [stop]
    page.click("#editor")
    page.keyboard.press("Control+End")  # the cursor away from the problem
    problem.locator("button", has_text="show").click()
    assert active_line_number(page) == str(stop)
    assert page.locator(".cm-activeLine .cm-problem-note").text_content().startswith("the document is not valid JSON")
    screenshot(page, "editor-03-json-syntax-error")


def test_line_numbers_are_shown(page):
    numbers = page.evaluate("""() => [...document.querySelectorAll('.cm-lineNumbers .cm-gutterElement')]
        .filter((e) => getComputedStyle(e).visibility !== 'hidden').map((e) => e.textContent)""")
    assert numbers[:5] == ["1", "2", "3", "4", "5"]
    assert document_text(page).startswith('{\n  "schema_version": 1')


def test_completion_offers_the_field_names_of_the_place(page):
    document = gripper()
    del document["elements"]["a"]["radius"]
    set_document_text(page, json.dumps(document, indent=2))
    select_field(page, "/elements/a/type")
    page.keyboard.press("End")
    page.keyboard.press("Enter")
    page.keyboard.type('"ra')
    options = page.locator(".cm-tooltip-autocomplete li")
    options.first.wait_for(timeout=10_000)
    offered = options.all_text_contents()
    assert any(o.startswith("radius") for o in offered), offered
    assert not any(o.startswith("position") for o in offered), offered  # a body's field, not a beam's
    screenshot(page, "editor-04-completion")
    page.wait_for_timeout(ACCEPT_AFTER_MS)
    page.keyboard.press("Enter")  # takes the first, the nearest match
    assert re.search(r'"type": "curved_beam",\n\s*"radius": \n', document_text(page))


def test_a_yaml_document_is_highlighted_completed_and_edited(page, log):
    log.answered = (422,)  # the page redraws while the text is typed: half a line is no YAML
    document = gripper()
    set_document_text(page, yaml.safe_dump(document, sort_keys=False))
    plain, colours = page.evaluate("""() => [getComputedStyle(document.querySelector('.cm-line')).color,
        [...document.querySelectorAll('.cm-line span')].map((s) => getComputedStyle(s).color)]""")
    assert colours and set(colours) - {plain}, colours  # the keys in their own colour
    select_field(page, "/bodies/frame/fixed")
    page.keyboard.press("End")
    page.keyboard.press("Enter")
    page.keyboard.type("ma")
    options = page.locator(".cm-tooltip-autocomplete li")
    options.first.wait_for(timeout=10_000)
    offered = options.all_text_contents()
    assert any(o.startswith("mass") for o in offered) and not any(o.startswith("fixed") for o in offered), offered
    page.wait_for_timeout(ACCEPT_AFTER_MS)
    page.keyboard.press("Enter")
    page.keyboard.type("0.001")
    select_field(page, "/name")
    page.keyboard.type("name: edited gripper")  # the page redraws after typing
    page.wait_for_function("() => document.getElementById('mechanism-name').textContent === 'edited gripper'")
    screenshot(page, "editor-05-yaml")
