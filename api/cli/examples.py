"""`flexmech examples`: the example documents and their names."""

from __future__ import annotations

import json

from rich.table import Table

from flexmech.api.cli.application import app
from flexmech.api.cli.common import OptionError, consoles, shown, user_errors
from flexmech.service.examples import examples_directory


@app.command()
def examples() -> None:
    """List the example documents and their names."""
    out, err = consoles()
    with user_errors(err):
        directory = examples_directory()
        if directory is None:
            raise OptionError("examples", "the package's examples are missing (a broken install: reinstall flexmech)")
        table = Table(title=f"examples (in {shown(str(directory))}): flexmech solve NAME", title_justify="left")
        table.add_column("name")
        table.add_column("title")
        for file in sorted(directory.glob("*.json")):
            try:
                data = json.loads(file.read_text())
                name = data.get("name", "") if isinstance(data, dict) else "(not a mechanism document)"
            except (OSError, json.JSONDecodeError) as exc:
                name = f"(unreadable: {exc})"
            table.add_row(file.stem, shown(str(name)))
        out.print(table)
