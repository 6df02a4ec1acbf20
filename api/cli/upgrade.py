"""`flexmech upgrade DOC`: a document of an older shape in today's (models.documents.upgrade), printed,
written to --output, or written over DOC with --in-place; what changed goes to stderr."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated

import typer

from flexmech.api.cli.application import app
from flexmech.api.cli.common import OptionError, consoles, shown, user_errors


@app.command()
def upgrade(
    document: Annotated[Path, typer.Argument(help="A mechanism document (JSON or YAML).")],
    output: Annotated[
        Path | None, typer.Option("--output", "-o", help="Write the upgraded document here (default: print it).")
    ] = None,
    in_place: Annotated[bool, typer.Option("--in-place", help="Write it over DOC.")] = False,
) -> None:
    """Convert a document of an older shape (an `impacts` section) to today's."""
    import yaml

    from flexmech.models.documents.reading import parse_json, parse_yaml
    from flexmech.models.documents.upgrade import upgraded
    from flexmech.models.errors import MechanismError

    out, err = consoles()
    with user_errors(err):
        if in_place and output is not None:
            raise OptionError("--in-place", "give --in-place or --output, not both")
        yaml_text = document.suffix.lower() in (".yaml", ".yml")
        try:
            text = document.read_bytes()
        except OSError as exc:
            raise MechanismError("", f"cannot read {document}: {exc.strerror}") from None
        data = parse_yaml(text, str(document)) if yaml_text else parse_json(text, str(document))
        new, changes = upgraded(data)
        written = yaml.safe_dump(new, sort_keys=False) if yaml_text else json.dumps(new, indent=2) + "\n"
        target = document if in_place else output
        if target is None:
            typer.echo(written, nl=False)
        else:
            try:
                target.write_text(written)
            except OSError as exc:
                raise OptionError(
                    "--output" if output is not None else "--in-place", f"cannot write {target}: {exc.strerror}"
                ) from None
        for change in changes:
            err.print(shown(change))
        err.print(
            f"{len(changes)} change{'s' if len(changes) != 1 else ''}"
            + ("" if changes else ": the document is in today's shape")
        )
