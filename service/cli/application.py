"""The typer app every command module registers its command on (service.cli imports them)."""

from __future__ import annotations

import typer

app = typer.Typer(
    name="flexmech",
    help="Kinetostatics of planar compliant mechanisms described by a mechanism document.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_show_locals=False,
)
