"""The command group of `flexmech`: the commands of its modules (api.cli imports them),
then one per registered analysis that has no command of its own (`flexmech modes DOC`,
`flexmech frf DOC`, and any a plugin registers).

The analyses' commands are made from their options models, which the registry holds, and the
registry imports the physics. So until the registry is imported (by a plugin, a test, or a
command that runs), `flexmech --help` lists the built-in analyses from api.cli.catalog, and
only when one of their commands is run (or asked for its --help) is the registry imported and
the real command made (api.cli.analysis_commands)."""

from __future__ import annotations

from collections.abc import Collection
from typing import Any

import typer.core

from flexmech.api.cli.catalog import catalog_entries, command_names, loaded_registry


class Listed(typer.core.TyperCommand):
    """An analysis' command as the list of commands shows it before the registry is imported;
    the group runs the real one in its place."""


class Commands(typer.core.TyperGroup):
    """The modules' commands, then the analyses' (Listed until the registry is there). Typer
    makes the group anew for every run of the app, so it holds the analyses registered by then."""

    def __init__(self, **attrs: Any):
        super().__init__(**attrs)
        self.own = set(self.commands)
        self.commands.update(analysis_commands(self.own))

    def resolve_command(self, ctx: Any, args: list[str]) -> tuple[str | None, Any, list[str]]:
        name, command, rest = super().resolve_command(ctx, args)
        if isinstance(command, Listed):  # it runs: its options come from the registry
            command = analysis_commands(self.own, load=True)[str(command.name)]
        if command is not None:
            plain_flags(command, ctx)
        return name, command, rest

    def get_params(self, ctx: Any) -> list[Any]:
        params = super().get_params(ctx)
        plain_flags_of(params)
        return params


def plain_flags(command: Any, ctx: Any) -> None:
    """A command's flags (--stiffness, --line-search/--no-line-search, --help) take no value:
    its --help shows no type for them (typer's would be <bool>)."""
    plain_flags_of(command.get_params(ctx))


def plain_flags_of(params: list[Any]) -> None:
    for param in params:
        if getattr(param, "is_flag", False) and param.metavar is None:
            param.metavar = ""


def analysis_commands(taken: Collection[str], load: bool = False) -> dict[str, Any]:
    """Command name -> the command of each analysis no command in `taken` has: made from the
    registry when it is imported (or `load` imports it), else Listed from the catalog."""
    registry = loaded_registry()
    if registry is None:
        if not load:
            return {
                command: Listed(name=command, short_help=short)
                for command, _, short in command_names(catalog_entries(), taken)
            }
        from flexmech.service.analyses import ANALYSES

        registry = ANALYSES
    from flexmech.api.cli.analysis_commands import commands_of

    return commands_of(registry, taken)
