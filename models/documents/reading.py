"""Reading JSON and YAML text strictly and within bounds: a duplicate key is an error (not a
silent merge), nesting deeper than MAX_DEPTH is refused, and so are integers too long to
convert and text that is not UTF-8. Every problem is a MechanismError naming what is wrong."""

from __future__ import annotations

import json
from typing import Any

import yaml

from flexmech.models.errors import MechanismError

MAX_DEPTH = 64  # a mechanism document nests about 6 deep; requests a few more


class DuplicateKey(ValueError):
    def __init__(self, key: str):
        self.key = key
        super().__init__(f"duplicate key '{key}' in one object")

    def __reduce__(self):  # pickled with its field (pickle's default passes the message as the key)
        return (DuplicateKey, (self.key,))


def _no_duplicates(pairs: list[tuple[str, Any]]) -> dict:
    out: dict = {}
    for key, value in pairs:
        if key in out:
            raise DuplicateKey(key)
        out[key] = value
    return out


def depth_of(value: Any) -> int:
    """How deep objects and arrays nest (iteratively: no recursion on hostile input)."""
    deepest, stack = 0, [(value, 1)]
    while stack:
        item, depth = stack.pop()
        if isinstance(item, dict):
            items = item.values()
        elif isinstance(item, list):
            items = item
        else:
            continue
        deepest = max(deepest, depth)
        if deepest > MAX_DEPTH:
            return deepest
        stack.extend((child, depth + 1) for child in items)
    return deepest


def _check_depth(value: Any, what: str) -> Any:
    if depth_of(value) > MAX_DEPTH:
        raise MechanismError("", f"{what} nests deeper than {MAX_DEPTH} levels")
    return value


def parse_json(text: str | bytes, what: str = "the document") -> Any:
    """JSON text to Python values; MechanismError("", ...) for anything malformed."""
    try:
        if isinstance(text, bytes):
            text = text.decode("utf-8")
        return _check_depth(json.loads(text, object_pairs_hook=_no_duplicates), what)
    except MechanismError:  # too deep: already said (it is a ValueError too)
        raise
    except DuplicateKey as exc:
        raise MechanismError("", f"{what} is not valid JSON: {exc}") from None
    except UnicodeDecodeError as exc:
        raise MechanismError("", f"{what} is not UTF-8 text (byte {exc.start})") from None
    except json.JSONDecodeError as exc:
        raise MechanismError("", f"{what} is not valid JSON: {exc}") from None
    except RecursionError:
        raise MechanismError("", f"{what} nests deeper than {MAX_DEPTH} levels") from None
    except ValueError as exc:  # e.g. an integer of more than 4300 digits
        raise MechanismError("", f"{what} is not valid JSON: {str(exc)[:200]}") from None


class _StrictLoader(yaml.SafeLoader):
    """PyYAML's safe loader, refusing a key given twice in one mapping."""

    def construct_mapping(self, node, deep=False):
        keys = set()
        for key_node, _ in node.value:
            key = self.construct_object(key_node, deep=deep)
            if not isinstance(key, (str, int, float, bool)) and key is not None:
                raise yaml.constructor.ConstructorError(
                    None, None, "a mapping key must be a string", key_node.start_mark
                )
            if key in keys:
                raise DuplicateKey(str(key))
            keys.add(key)
        return super().construct_mapping(node, deep=deep)


class _NoAliasLoader(_StrictLoader):
    """Refuses aliases: text from a network could make a few lines of them expand into a
    document too large to walk or answer (the "billion laughs")."""

    def compose_node(self, parent, index):
        if self.check_event(yaml.AliasEvent):
            mark = self.peek_event().start_mark
            raise yaml.composer.ComposerError(
                None, None, "aliases (*name) are not accepted here: write the value out", mark
            )
        return super().compose_node(parent, index)


def parse_yaml(text: str | bytes, what: str = "the document", aliases: bool = True) -> Any:
    """YAML text to Python values (safe tags only; with aliases=False, no aliases either);
    MechanismError for anything malformed."""
    loader = _StrictLoader if aliases else _NoAliasLoader
    try:
        if isinstance(text, bytes):
            text = text.decode("utf-8")
        return _check_depth(yaml.load(text, Loader=loader), what)  # noqa: S506 (a SafeLoader)
    except DuplicateKey as exc:
        raise MechanismError("", f"{what} is not valid YAML: {exc}") from None
    except UnicodeDecodeError as exc:
        raise MechanismError("", f"{what} is not UTF-8 text (byte {exc.start})") from None
    except yaml.YAMLError as exc:
        raise MechanismError("", f"{what} is not valid YAML: {str(exc)[:300]}") from None
    except RecursionError:
        raise MechanismError("", f"{what} nests deeper than {MAX_DEPTH} levels") from None
