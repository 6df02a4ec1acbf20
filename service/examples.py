"""The example mechanism documents shipped with flexmech (flexmech.examples: the repository's
examples/, installed with the package), found by name everywhere: the CLI's document argument,
flexmech.load, {"example": ...} over HTTP and the page."""

from __future__ import annotations

import json
from dataclasses import dataclass
from importlib.resources import files
from pathlib import Path


def examples_directory(configured: Path | None = None) -> Path | None:
    """`configured` if given, else the examples installed with the package."""
    if configured is not None:
        return configured if configured.is_dir() else None
    shipped = Path(str(files("flexmech.examples")))
    return shipped if shipped.is_dir() else None


def document_path(given: str | Path) -> Path:
    """A document's file: `given` when it is a path (it exists, or has a folder or a suffix),
    else the shipped example of that name (gripper: .../examples/gripper.json). MechanismError
    when it is neither, listing the examples."""
    from flexmech.models import MechanismError  # here: the CLI's --help imports this module, never the physics

    path = Path(given)
    if path.exists() or path.suffix or len(path.parts) != 1:
        return path
    directory = examples_directory()
    found = directory / f"{path.name}.json" if directory is not None else None
    if found is not None and found.is_file():
        return found
    names = ", ".join(sorted(f.stem for f in directory.glob("*.json"))) if directory is not None else "none"
    raise MechanismError("", f"no file '{given}' and no example of that name (examples: {names})")


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
