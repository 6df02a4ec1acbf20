"""The Python in the README and the docs runs (issue 48): every ```pycon block of a page is a
doctest (the blocks of one page share their names), run outside the checkout as a user would,
the HTTP ones against a live server ($FLEXMECH_URL); and no page shows an import of the private
floors (models, service, api) as if they were packages of their own."""

from __future__ import annotations

import doctest
import io
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PAGES = [ROOT / "README.md", ROOT / "CONTRIBUTING.md", *sorted((ROOT / "docs").glob("*.md"))]
PYCON = re.compile(r"```pycon\n(.*?)```", re.S)
FENCED = re.compile(r"```\w*\n(.*?)```", re.S)
OLD_IMPORT = re.compile(r"^\s*(?:>>> )?(?:from|import) (?:models|service|api)\b", re.M)


@pytest.mark.parametrize(
    "page", [p for p in PAGES if PYCON.search(p.read_text())], ids=lambda p: str(p.relative_to(ROOT))
)
def test_a_pages_python_runs(page, api_server, monkeypatch, tmp_path):
    monkeypatch.setenv("FLEXMECH_URL", api_server.url)
    monkeypatch.delenv("FLEXMECH_API_KEY", raising=False)
    monkeypatch.chdir(tmp_path)  # examples by name, from anywhere
    text = "\n".join(PYCON.findall(page.read_text()))
    test = doctest.DocTestParser().get_doctest(text, {}, page.name, str(page), 0)
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    report = io.StringIO()
    runner.run(test, out=report.write)
    assert test.examples and runner.failures == 0, report.getvalue()


def test_no_page_imports_a_floor_as_a_package_of_its_own():
    found = [
        f"{page.relative_to(ROOT)}: {line.strip()}"
        for page in PAGES
        for block in FENCED.findall(page.read_text())
        for line in OLD_IMPORT.findall(block)
    ]
    assert not found, found
