"""The example mechanism documents shipped with flexmech (examples/*.json)."""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path


def examples_directory(configured: Path | None = None) -> Path | None:
    """`configured` if given, else examples/ of the current directory, else the one next to
    the package sources."""
    candidates = (
        [configured]
        if configured is not None
        else [Path.cwd() / "examples", Path(__file__).resolve().parents[1] / "examples"]
    )
    for candidate in candidates:
        if candidate.is_dir():
            return candidate
    return None


@dataclass(frozen=True)
class Example:
    name: str  # file name without .json
    title: str
    description: str
    document: dict


class ExampleLibrary:
    """Example documents by name, read once."""

    def __init__(self, directory: Path | None):
        self.directory = directory
        self._examples: dict[str, Example] = {}
        if directory is None:
            return
        for file in sorted(directory.glob("*.json")):
            try:
                data = json.loads(file.read_text())
            except (OSError, json.JSONDecodeError):
                continue  # not an example; `flexmech examples` reports unreadable files
            if isinstance(data, dict):
                self._examples[file.stem] = Example(
                    file.stem, str(data.get("name", file.stem)), str(data.get("description", "")), data
                )

    def names(self) -> list[str]:
        return list(self._examples)

    def get(self, name: str) -> Example | None:
        return self._examples.get(name)

    def all(self) -> list[Example]:
        return list(self._examples.values())
