"""The typer app every command module registers its command on (api.cli imports them); its
group adds a command per analysis (api.cli.commands)."""

from __future__ import annotations

import typer

from flexmech.api.cli.commands import Commands

app = typer.Typer(
    name="flexmech",
    cls=Commands,
    help="Kinetostatics of planar compliant mechanisms described by a mechanism document.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_show_locals=False,
)


def _version(asked: bool) -> None:
    if asked:
        from importlib.metadata import PackageNotFoundError, version

        try:
            typer.echo(f"flexmech {version('flexmech')}")
        except PackageNotFoundError:  # the sources without an install
            typer.echo("flexmech (not installed)")
        raise typer.Exit()


@app.callback()
def _options(
    version: bool = typer.Option(
        False, "--version", callback=_version, is_eager=True, help="Print the version and exit."
    ),
) -> None:
    """Kinetostatics of planar compliant mechanisms described by a mechanism document."""
