"""The documentation (issue 26): README.md a short entry (what it is, the two commands, a tour
with one figure, where to go next), the rest a MkDocs site in docs/ that builds in strict mode
(a broken link or a page left out of the navigation fails), and an architecture page that says
where to add each kind of thing."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[2]


def test_the_site_builds_in_strict_mode(tmp_path):
    done = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(tmp_path / "site")],
        cwd=ROOT,
        capture_output=True,
        text=True,
        env={**os.environ, "NO_MKDOCS_2_WARNING": "1"},
    )
    assert done.returncode == 0, done.stdout + done.stderr
    assert (tmp_path / "site" / "dynamics" / "index.html").exists()


def test_the_readme_is_short_and_leads_to_every_page():
    readme = (ROOT / "README.md").read_text()
    assert len(readme.splitlines()) <= 250
    pages = [next(iter(entry.values())) for entry in yaml.safe_load((ROOT / "mkdocs.yml").read_text())["nav"]]
    linked = set(re.findall(r"\]\(docs/([\w.-]+\.md)\)", readme))
    assert set(pages) - {"index.md"} == linked
    assert {path.name for path in (ROOT / "docs").glob("*.md")} == set(pages)  # no page outside the navigation
    commands = re.findall(r"```bash\n(.*?)```", readme.split("## Using it")[0], re.S)
    assert len(commands) == 2  # the two set-up commands: the main job, the tests


def test_the_architecture_page_says_where_to_add_each_kind_of_thing():
    page = (ROOT / "docs" / "architecture.md").read_text()
    table = page.split("## Where to add")[1].split("\n## ")[0]
    rows = [line.split("|")[1].strip() for line in table.splitlines() if line.startswith("| ") and "---" not in line]
    assert rows[1:] == ["an element family", "a contact law", "an output", "an analysis", "a job kind"]
