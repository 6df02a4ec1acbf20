"""A real headless Chromium (Debian's package) driven by Playwright, for the workbench's
end-to-end tests: every request, console message and page error of its pages is recorded,
and screenshots go to out/workbench/."""

from __future__ import annotations

import shutil
import subprocess
from dataclasses import dataclass, field
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
SCREENSHOTS = REPO / "out" / "workbench"
# Without the background-networking flags Chromium calls Google's hosts at start (refused here).
CHROMIUM_FLAGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--disable-default-apps",
    "--disable-extensions",
    "--metrics-recording-only",
    "--no-default-browser-check",
]


def _installed_chromium() -> str | None:
    for name in ("chromium", "chromium-browser", "google-chrome"):
        found = shutil.which(name)
        if found:
            return found
    return None


def chromium_path() -> str:
    """Debian's Chromium, installed first by scripts/chromium-for-tests (apt-get) if missing."""
    found = _installed_chromium()
    if found is None:
        done = subprocess.run([str(REPO / "scripts" / "chromium-for-tests")], capture_output=True, text=True)
        found = _installed_chromium()
        if found is None:
            raise RuntimeError(
                "Chromium not found, and scripts/chromium-for-tests could not install the Debian "
                f"package 'chromium' (exit {done.returncode}): {done.stderr[-2000:]}"
            )
    return found


@dataclass
class PageLog:
    """What a page did: the URL of every request, console messages, uncaught errors."""

    requests: list[str] = field(default_factory=list)
    console: list[tuple[str, str]] = field(default_factory=list)
    errors: list[str] = field(default_factory=list)
    answered: tuple[int, ...] = ()  # error statuses the test provokes on purpose

    def watch(self, page) -> None:
        page.on("request", lambda request: self.requests.append(request.url))
        page.on("console", lambda message: self.console.append((message.type, message.text)))
        page.on("pageerror", lambda error: self.errors.append(str(error)))

    def problems(self, answered: tuple[int, ...] = ()) -> list[str]:
        """Console errors and warnings, and uncaught exceptions. Chromium logs every 4xx answer
        as an error ("Failed to load resource"); those of the statuses `answered` (a refusal
        the test provoked and the page shows) are not problems."""
        expected = tuple(f"the server responded with a status of {status} " for status in answered)
        return [
            f"{kind}: {text}"
            for kind, text in self.console
            if kind in ("error", "warning") and not any(e in text for e in expected)
        ] + self.errors


def screenshot(page, name: str) -> Path:
    SCREENSHOTS.mkdir(parents=True, exist_ok=True)
    path = SCREENSHOTS / f"{name}.png"
    page.screenshot(path=str(path), full_page=True)
    return path
