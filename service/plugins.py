"""Plugins: modules named in FLEXMECH_PLUGINS (comma-separated, importable names), imported by
every process that takes from the registries (the server and its workers, the CLI, batch), so
an analysis, element family or contact law a plugin registers is served, offered and run
everywhere without a change here."""

from __future__ import annotations

import importlib
import os

ENVIRONMENT = "FLEXMECH_PLUGINS"


class PluginError(ImportError):
    """A module FLEXMECH_PLUGINS names cannot be imported."""


def plugin_names(value: str | None = None) -> list[str]:
    text = os.environ.get(ENVIRONMENT, "") if value is None else value
    return [name.strip() for name in text.split(",") if name.strip()]


def load_plugins(value: str | None = None) -> list[str]:
    """Import each plugin module (once: Python keeps them); the names imported."""
    names = plugin_names(value)
    for name in names:
        try:
            importlib.import_module(name)
        except ImportError as exc:
            raise PluginError(f"{ENVIRONMENT} names '{name}', which cannot be imported: {exc}") from exc
    return names
