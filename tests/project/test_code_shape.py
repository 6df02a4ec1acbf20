"""The shape of the code (issue 11): small modules and functions, private names kept private,
no import cycles. Read from the sources with ast, nothing imported."""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
FLOORS = ("models", "service", "api")  # folders of the repository, installed as flexmech.<floor>
MAX_MODULE_LINES = 400
MAX_FUNCTION_LINES = 60


def modules() -> dict[str, Path]:
    """Dotted module name (as installed: flexmech.service.jobs.sweep) -> file, for every module
    of the package: the three floors and flexmech/ itself."""
    found = {}
    for folder in ("flexmech", *FLOORS):
        for path in sorted((ROOT / folder).rglob("*.py")):
            parts = list(path.relative_to(ROOT).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts.pop()
            found[".".join(parts if folder == "flexmech" else ["flexmech", *parts])] = path
    return found


def trees() -> dict[str, ast.Module]:
    return {name: ast.parse(path.read_text(), str(path)) for name, path in modules().items()}


def imported(name: str, tree: ast.Module, known: set[str]) -> list[tuple[str, str | None]]:
    """(module, imported name or None) for every import of a flexmech module, anywhere in it."""
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out += [(alias.name, None) for alias in node.names if alias.name.split(".")[0] == "flexmech"]
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            if node.module.split(".")[0] != "flexmech":
                continue
            for alias in node.names:
                sub = f"{node.module}.{alias.name}"
                out.append((sub, None) if sub in known else (node.module, alias.name))
    return out


def test_modules_are_small():
    long = {name: len(path.read_text().splitlines()) for name, path in modules().items()}
    assert not {name: n for name, n in long.items() if n > MAX_MODULE_LINES}


def test_functions_are_short():
    long = []
    for name, tree in trees().items():
        for node in ast.walk(tree):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                start = min([node.lineno, *(d.lineno for d in node.decorator_list)])
                if node.end_lineno - start + 1 > MAX_FUNCTION_LINES:
                    long.append(f"{name}.{node.name}: {node.end_lineno - start + 1} lines")
    assert not long


def test_private_names_stay_in_their_module():
    known = set(modules())
    used = []
    for name, tree in trees().items():
        aliases = {}
        for module, item in imported(name, tree, known):
            if item is not None and item.startswith("_") and not item.startswith("__"):
                used.append(f"{name} imports {module}.{item}")
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                aliases.update({(a.asname or a.name): a.name for a in node.names})
            elif isinstance(node, ast.ImportFrom) and node.module and f"{node.module}.{node.names[0].name}" in known:
                aliases.update({(a.asname or a.name): f"{node.module}.{a.name}" for a in node.names})
        for node in ast.walk(tree):
            if (
                isinstance(node, ast.Attribute)
                and isinstance(node.value, ast.Name)
                and node.value.id in aliases
                and aliases[node.value.id] in known
                and node.attr.startswith("_")
                and not node.attr.startswith("__")
            ):
                used.append(f"{name} uses {aliases[node.value.id]}.{node.attr}")
    assert not used


def test_no_import_cycles():
    known = set(modules())
    graph = {
        name: {module for module, _ in imported(name, tree, known) if module in known and module != name}
        for name, tree in trees().items()
    }
    cycles, state = [], {}

    def visit(node: str, path: list[str]) -> None:
        state[node] = "open"
        for nxt in sorted(graph[node]):
            if state.get(nxt) == "open":
                cycles.append(" -> ".join(path[path.index(nxt) :] + [node, nxt]) if nxt in path else f"{node} -> {nxt}")
            elif nxt not in state:
                visit(nxt, path + [node])
        state[node] = "done"

    for name in sorted(graph):
        if name not in state:
            visit(name, [])
    assert not cycles


def test_every_import_of_ours_goes_through_the_one_package():
    """`from flexmech.models import ...`, never `from models import ...`: a checkout's floors are
    importable as top-level packages only from its root (tests, a developer's shell), never where
    the package is installed, so such an import works here and fails for users. The tests,
    benchmarks, scripts and examples are read too."""
    found = []
    for folder in ("flexmech", *FLOORS, "tests", "benchmarks", "examples"):
        for path in sorted((ROOT / folder).rglob("*.py")):
            for node in ast.walk(ast.parse(path.read_text(), str(path))):
                names = (
                    [a.name for a in node.names]
                    if isinstance(node, ast.Import)
                    else [node.module]
                    if isinstance(node, ast.ImportFrom) and node.module and node.level == 0
                    else []
                )
                found += [f"{path.relative_to(ROOT)}:{node.lineno} {n}" for n in names if n.split(".")[0] in FLOORS]
    assert not found, found


def test_each_floor_imports_only_the_floors_below():
    """models/ imports neither service/ nor api/, service/ never api/ (DESIGN.md: the floors);
    the public surface flexmech/ may import any."""
    below = {"models": {"models"}, "service": {"models", "service"}, "api": {"models", "service", "api"}}
    known = set(modules())
    found = []
    for name, tree in trees().items():
        parts = name.split(".")
        if len(parts) < 2 or parts[1] not in below:
            continue
        for module, _ in imported(name, tree, known):
            floor = module.split(".")[1] if module.count(".") else ""
            if floor not in below[parts[1]]:
                found.append(f"{name} imports {module}")
    assert not found, found


def element_types() -> set[str]:
    """The element families' type names, as their modules declare them (`type = "..."`)."""
    names = set()
    for path in (ROOT / "models" / "elements").glob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if (
                isinstance(node, ast.Assign)
                and any(isinstance(t, ast.Name) and t.id == "type" for t in node.targets)
                and isinstance(node.value, ast.Constant)
                and isinstance(node.value.value, str)
            ):
                names.add(node.value.value)
    return names


def element_classes() -> set[str]:
    """The classes models/elements defines (an element's schema, topology, family)."""
    return {
        node.name
        for path in (ROOT / "models" / "elements").glob("*.py")
        for node in ast.walk(ast.parse(path.read_text()))
        if isinstance(node, ast.ClassDef)
    }


def _names(node: ast.AST) -> set[str]:
    if isinstance(node, ast.Name):
        return {node.id}
    if isinstance(node, ast.Attribute):
        return {node.attr}
    if isinstance(node, ast.Tuple):
        return set().union(set(), *(_names(item) for item in node.elts))
    return set()


def _strings(node: ast.AST) -> set[str]:
    if isinstance(node, ast.Constant) and isinstance(node.value, str):
        return {node.value}
    if isinstance(node, (ast.Tuple, ast.List, ast.Set)):
        return set().union(*(_strings(item) for item in node.elts)) if node.elts else set()
    return set()


def test_no_element_type_is_compared_outside_its_family():
    """Per-type questions go through the element registry (issue 26): a comparison with a
    family's name (an element's type or family, or anything else), a selection by a family's name
    (Structure.of_family) or an isinstance of an element class belongs in models/elements only."""
    types, classes = element_types(), element_classes() - {"TwoBodyElement"}  # the base of every schema
    assert {"link", "link_elements", "curved_beam", "spring", "pin", "slider"} <= types
    assert {"LinkElementsTopology", "FlexureTopology", "CurvedBeam"} <= classes
    found = []
    for name, tree in trees().items():
        if name.startswith("flexmech.models.elements"):
            continue
        for node in ast.walk(tree):
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == "isinstance":
                named = _names(node.args[1]) & classes if len(node.args) == 2 else set()
                if named:
                    found.append(f"{name}:{node.lineno} asks isinstance of {', '.join(sorted(named))}")
                continue
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "of_family":
                named = set().union(set(), *(_strings(arg) for arg in node.args)) & types
                if named:
                    found.append(f"{name}:{node.lineno} selects the family {', '.join(sorted(named))}")
                continue
            if not isinstance(node, ast.Compare):
                continue
            named = set().union(*(_strings(side) for side in [node.left, *node.comparators])) & types
            if named:
                found.append(f"{name}:{node.lineno} compares with {', '.join(sorted(named))}")
    assert not found, found


def test_no_two_modules_of_models_share_a_name():
    """Rooms that show the shape (issue 26): a module's name says which one it is."""
    seen: dict[str, list[str]] = {}
    for name in modules():
        if name.startswith("flexmech.models.") and not name.endswith("__init__"):
            seen.setdefault(name.rsplit(".", 1)[1], []).append(name)
    assert not {stem: names for stem, names in seen.items() if len(names) > 1}


# The one parser of the Newton options object (into NewtonOptions, naming a bad field), and
# the document's inverse shapes (free-form in the document's schema: not a request's options).
DICT_READERS_ALLOWED = {"flexmech.service.requests", "flexmech.service.solvers.inverse_links"}
REQUEST_NAMES = ("spec", "request", "given", "options")


def test_no_module_outside_api_reads_request_options_from_a_dict():
    """Requests are typed where they arrive (issue 26): an analysis reads its Options model, a
    job kind its typed spec (service.jobs.base.read_spec); nothing in models/ or service/ reads
    a request's field out of a dict (`spec.get("x")`, `request["x"]`, ...)."""
    found = []
    for name, tree in trees().items():
        if name.startswith("flexmech.api") or name in DICT_READERS_ALLOWED:
            continue
        names = REQUEST_NAMES + (("stored",) if name.startswith("flexmech.service.jobs") else ())  # a kind's raw spec
        for node in ast.walk(tree):
            read = None
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "get":
                read = node.func.value
            elif isinstance(node, ast.Subscript) and isinstance(node.slice, ast.Constant):
                read = node.value if isinstance(node.slice.value, str) else None
            if isinstance(read, ast.Name) and read.id in names:
                found.append(f"{name}:{node.lineno} reads {read.id}[...]")
    assert not found, found
