"""The residual form of a structure (seed 000 Eqs. 3-28, for any number of bodies and of
elements of any family) and the Functions every analysis calls.

Residual per free body coordinate (generalized force on x, y, angle):
    R_b = sum over elements of the wrench body b applies to them - the applied wrench
then every element's own rows. Rows of prescribed coordinates are support reactions.
Unknowns z: the free body displacements, then each element's own unknowns, in document order.

Graphs are built once per structure (numbers are parameters), for the structure without its
names (models.documents.naming: a renamed mechanism shares them), and kept in memory and on disk
(models.caches.graph_cache); the seed-000 split of K_T (models.graph.tangent_split) and the energy and
mass forms (models.graph.forms) are built on demand.
"""

from __future__ import annotations

import logging
from functools import cached_property, lru_cache

import casadi as ca

from flexmech.models.caches.graph_cache import GraphStore
from flexmech.models.documents.naming import named
from flexmech.models.elements import FAMILIES
from flexmech.models.graph.context import AssemblyContext
from flexmech.models.graph.loads import applied_wrenches
from flexmech.models.graph.outputs import output_graph, shape_graph
from flexmech.models.graph.residual import contributions, held_wrenches, residual_of
from flexmech.models.graph.split_jacobian import jacobian
from flexmech.models.graph.structure import Structure

log = logging.getLogger("flexmech.graphs")

# The Functions of the residual form, by name; each is (z, p) -> ... unless noted.
FUNCTIONS = ("residual", "residual_and_tangent", "body_wrenches", "displacements", "outputs", "shapes")
REPORTING = ("outputs", "shapes")  # what a report of given states needs (Graphs.prefer_reporting)


@lru_cache(maxsize=2)
def _symbolic(structure: Structure):
    """The residual form's expressions: kept for the few latest structures, so that the whole
    build after the reporting one (service.dynamics reports, then a statics analysis) does
    not build them again."""
    ctx = AssemblyContext(structure)
    z = ca.SX.sym("z", structure.n_unknowns)
    d = ctx.displacements(z)
    return ctx, z, d, contributions(ctx, z, d), applied_wrenches(ctx, d)


def _reporting(ctx, z, d, parts, applied) -> tuple[dict[str, ca.Function], dict]:
    functions = {}
    functions["outputs"], names, kinds = output_graph(ctx, z, d, parts, applied)
    functions["shapes"], segments = shape_graph(ctx, z, parts)
    return functions, {"output_names": names, "output_kinds": kinds, "shape_segments": segments}


def build_reporting(structure: Structure) -> tuple[dict[str, ca.Function], dict]:
    """The outputs and shapes alone (without the residual and its tangent, the most of a
    large structure's build): for reporting states found by other means (the kernels'
    time steps)."""
    return _reporting(*_symbolic(structure))


def build_functions(structure: Structure) -> tuple[dict[str, ca.Function], dict]:
    """The residual form's Functions and their metadata (output names and kinds, segments)."""
    ctx, z, d, parts, applied = _symbolic(structure)
    p = ctx.p
    # No pass of CasADi's cse over the residual (0.1-0.17 s of a large structure's first
    # solve): the families write no common subexpression twice (a link's steps share their
    # first slope, its unloaded nodes are merged per link), so it would merge less than 0.2%.
    R = residual_of(ctx, parts, applied)
    K = jacobian(R, z)
    functions = {
        "residual": ca.Function("residual", [z, p], [R], ["z", "p"], ["R"]),
        "residual_and_tangent": ca.Function("residual_and_tangent", [z, p], [R, K], ["z", "p"], ["R", "K"]),
        "body_wrenches": _body_wrenches(ctx),
        "displacements": ca.Function("displacements", [z, p], [ca.vertcat(*d)], ["z", "p"], ["d"], dict(cse=True)),
    }
    reporting, meta = _reporting(ctx, z, d, parts, applied)
    functions.update(reporting)
    for f in functions.values():
        if f.has_free():
            raise RuntimeError(f"graph {f.name()} has free symbols {f.get_free()}")
    return functions, meta


def residual_by_rows(structure: Structure) -> list[tuple[list[int], ca.Function]]:
    """R and its tangent K by row groups: the free body rows, then each element's own rows, as
    (rows, (z, p) -> (R[rows], K[rows, :])). For generated code: a C compiler's optimizer takes
    more than linearly longer over one large function than over its parts (the exact gripper's
    whole R and K: 54 s at gcc -O2; by rows, 9% more code: 13 s)."""
    ctx, z, d, parts, applied = _symbolic(structure)
    R = residual_of(ctx, parts, applied)
    K = jacobian(R, z)
    n_body = len(structure.free)
    groups = [list(range(n_body))] if n_body else []
    groups += [
        list(range(o, o + t.unknowns)) for t, o in zip(structure.elements, structure.element_offsets) if t.unknowns
    ]
    return [
        (rows, ca.Function(f"residual_rows_{k}", [z, ctx.p], [R[rows], K[rows, :]], ["z", "p"], ["R", "K"]))
        for k, rows in enumerate(groups)
    ]


def _body_wrenches(ctx: AssemblyContext) -> ca.Function:
    """(d, p) -> (elastic, applied), 3 per body, d: every body's displacement. Elastic: the
    wrenches bodies apply to the elements that own no unknowns (their force follows from
    the body displacements alone)."""
    d_all = ca.SX.sym("d", 3 * ctx.n_bodies)
    d = [d_all[3 * b : 3 * b + 3] for b in range(ctx.n_bodies)]
    direct = [FAMILIES.of(t).contribute(ctx, t, d, ca.SX(0, 1)) for t in ctx.structure.elements if t.unknowns == 0]
    held = held_wrenches(ctx, direct)
    return ca.Function(
        "body_wrenches",
        [d_all, ctx.p],
        [ca.vertcat(*held), ca.vertcat(*applied_wrenches(ctx, d))],
        ["d", "p"],
        ["elastic", "applied"],
        dict(cse=True),
    )


class Graphs:
    """CasADi Functions of one structure. Inputs: z (free displacements and element unknowns,
    nondimensional), p (parameters, nondimensional). Each Function is loaded or built when
    first asked for, shared with every structure that differs only in its names."""

    def __init__(self, structure: Structure):
        self.structure = structure
        unnamed, self._names = structure.without_names
        self._store, self._reporting = _store_of(unnamed), _reporting_store_of(unnamed)
        self._reporting_first = False

    def prefer_reporting(self) -> None:
        """Serve the outputs and shapes from their own graphs while the whole residual form is
        neither built nor saved: for reports of states found by other means (a simulation's, on
        the element kernels), which then never build the residual and its tangent."""
        self._reporting_first = True

    def _serving(self, name: str) -> GraphStore:
        if name in REPORTING and self._reporting_first and not self._store.available():
            return self._reporting
        return self._store

    def _get(self, name: str) -> ca.Function:
        try:
            return self._serving(name).function(name)
        except Exception:
            if not self._names:
                raise
            # Build with the mechanism's own names: an error then names its own parts, and a
            # structure the renaming got wrong still gets its graphs (noted: it is a bug).
            self._store = GraphStore(self.structure, build_functions)
            self._reporting, self._names = GraphStore(self.structure, build_reporting, "reporting"), ()
            function = self._serving(name).function(name)
            log.warning("the graphs of structure %s built only with its own names", self.structure.key)
            return function

    def _meta(self, key: str):
        self._get("outputs")  # builds (or loads) the store that serves them, falling back as _get does
        return named(self._serving("outputs").meta[key], self._names)

    residual = property(lambda self: self._get("residual"))  # (z, p) -> R
    residual_and_tangent = property(lambda self: self._get("residual_and_tangent"))  # (z, p) -> (R, K)
    body_wrenches = property(lambda self: self._get("body_wrenches"))  # (d, p) -> (elastic, applied)
    displacements = property(lambda self: self._get("displacements"))  # (z, p) -> d
    outputs = property(lambda self: self._get("outputs"))  # (z, p) -> y
    shapes = property(lambda self: self._get("shapes"))  # (z, p) -> (deformed, undeformed): 2 x samples

    @cached_property
    def output_names(self) -> tuple[str, ...]:
        return tuple(self._meta("output_names"))

    @cached_property
    def output_kinds(self) -> tuple[str, ...]:
        return tuple(self._meta("output_kinds"))

    @cached_property
    def shape_segments(self) -> tuple[tuple[str, int, int, int, int], ...]:
        """Per element drawn: (name, first column in shapes, columns, start body, end body)."""
        return tuple(tuple(s) for s in self._meta("shape_segments"))

    @cached_property
    def energy_form(self):
        """The total potential and its constraints (models.graph.forms.EnergyForm); MechanismError
        naming the first element whose model has none."""
        from flexmech.models.graph.forms import energy_form

        return energy_form(self.structure)

    @cached_property
    def modal_form(self):
        """The stiffness, constraints and masses of small vibration (models.graph.modal);
        MechanismError as energy_form's."""
        from flexmech.models.graph.modal import modal_form

        return modal_form(self.structure)

    @cached_property
    def mass_matrix(self) -> ca.Function:
        """(z, p) -> M (models.graph.forms.mass_matrix)."""
        from flexmech.models.graph.forms import mass_matrix

        return mass_matrix(self.structure)

    @cached_property
    def tangent_terms(self) -> ca.Function:
        """(z, p) -> (K_I, K_II, K_III, K_load): the split of K_T of seed 000 (Eqs. 26-28)."""
        from flexmech.models.graph.tangent_split import tangent_terms

        return tangent_terms(self.structure)


@lru_cache(maxsize=16)
def graphs_for(structure: Structure) -> Graphs:
    """Graphs of a structure, built once per process and reused for every parameter value.
    Few are kept in memory: a structure seen before loads from disk in milliseconds."""
    return Graphs(structure)


@lru_cache(maxsize=16)
def _store_of(unnamed: Structure) -> GraphStore:
    """The Functions of a structure without names (models.documents.naming), shared by its renamings."""
    return GraphStore(unnamed, build_functions)


@lru_cache(maxsize=16)
def _reporting_store_of(unnamed: Structure) -> GraphStore:
    return GraphStore(unnamed, build_reporting, "reporting")
