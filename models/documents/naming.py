"""A structure without its names: what two mechanisms that differ only in what they call
their bodies, elements, loads, outputs, materials, sections and contacts have in common.

Graphs depend on names only through labels (output names, drawn segments) and through the
pointers that find a number among the parameters. Replacing every name by a token in order
of first appearance (a bijection applied to the name fields and to the name segment of
every pointer, nowhere else) gives a structure whose graphs serve every renaming of it; the
labels of its metadata are turned back into a mechanism's own names by `named`. A name is
tokenized within its collection: an output called like its body ("J2" and "J2") and the same
output renamed are one structure.
"""

from __future__ import annotations

import re
from dataclasses import fields, is_dataclass, replace
from typing import Any

# Fields that hold the name of something the document names (a body, an element, a load, an
# output, a material, a section, a contact object, site or pair). Other strings are
# vocabulary (a model, a location, a law's parameter names) and stay as they are.
NAME_FIELDS = frozenset({"name", "material", "section", "element", "link", "bodies"})
POINTER_FIELDS = frozenset({"pointer", "prescribed"})
NAMED_SECTIONS = frozenset({"bodies", "elements", "loads", "outputs", "materials", "sections"})
TOKEN = re.compile(r"⟨(\d+)⟩")
# The collection of a `name` field, by the class that holds it (a class not listed: its own)
NAME_OWNERS = {
    "LoadTopology": "loads",
    "PointTopology": "outputs",
    "SectionTopology": "sections",
    "ObjectTopology": "contacts/objects",
    "SiteTopology": "contacts/sites",
    "PairTopology": "contacts/pairs",
}
FIELD_COLLECTIONS = {
    "material": "materials",
    "section": "sections",
    "bodies": "bodies",
    "element": "elements",
    "link": "elements",
}
# A name with these could be taken for a token ('/' and '~', which would split a pointer, are
# refused by models.graph.collect anyway): such a structure keeps its own names and graphs.
UNSAFE = re.compile(r"[/~⟨⟩]")


class _Renamer:
    def __init__(self):
        self.names: list[str] = []
        self.tokens: dict[tuple[str, str], str] = {}

    def token(self, name: str, collection: str) -> str:
        if UNSAFE.search(name):
            raise _Unsafe(name)
        key = (collection, name)
        if key not in self.tokens:
            self.tokens[key] = f"⟨{len(self.names)}⟩"
            self.names.append(name)
        return self.tokens[key]

    def pointer(self, pointer: str) -> str:
        parts = pointer.split("/")
        at = (
            3
            if len(parts) > 3 and parts[1] == "contacts"
            else 2
            if len(parts) > 2 and parts[1] in NAMED_SECTIONS
            else 0
        )
        if at:
            parts[at] = self.token(parts[at], "/".join(parts[1:at]))
        return "/".join(parts)

    def value(self, value: Any, role: str | None, collection: str = "") -> Any:
        if isinstance(value, str):
            if role == "name":
                return self.token(value, collection)
            return self.pointer(value) if role == "pointer" else value
        if isinstance(value, tuple):
            if role == "reactions":  # (output name, body)
                return tuple((self.token(name, "outputs"), body) for name, body in value)
            return tuple(self.value(item, role, collection) for item in value)
        if is_dataclass(value) and not isinstance(value, type):
            return replace(
                value,
                **{
                    f.name: self.value(getattr(value, f.name), _role(f.name), _collection(value, f.name))
                    for f in fields(value)
                    if f.init
                },
            )
        return value


class _Unsafe(Exception):
    pass


def _collection(holder: Any, field: str) -> str:
    """The collection whose names a field of `holder` holds: elements' names are their own."""
    if field != "name":
        return FIELD_COLLECTIONS.get(field, field)
    owner = type(holder).__name__
    return NAME_OWNERS.get(owner, "elements" if owner.endswith("Topology") else owner)


def _role(field: str) -> str | None:
    if field in NAME_FIELDS:
        return "name"
    if field in POINTER_FIELDS:
        return "pointer"
    return "reactions" if field == "reactions" else None


def anonymous(structure):
    """(the structure with its names replaced by tokens, the names in token order); the
    structure itself and no names when a name could be taken for a token."""
    renamer = _Renamer()
    try:
        return renamer.value(structure, None), tuple(renamer.names)
    except _Unsafe:
        return structure, ()


def named(value: Any, names: tuple[str, ...]) -> Any:
    """Labels of an anonymous structure's metadata (strings, in lists and dicts) with the
    tokens turned back into names."""
    if isinstance(value, str):
        return TOKEN.sub(lambda m: names[int(m.group(1))], value) if names else value
    if isinstance(value, (list, tuple)):
        return type(value)(named(item, names) for item in value)
    if isinstance(value, dict):
        return {named(k, names): named(v, names) for k, v in value.items()}
    return value
