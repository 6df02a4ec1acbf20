"""What an export's C costs, predicted from the compiled mechanism's structure before any code is
generated: a few operations per element, microseconds; nothing is built.

The generated C is almost all the residual and its tangent, one C function per row group
(models.graph.assembly.residual_by_rows: the free bodies' rows, then each element's own rows),
one line of about 25 bytes per SX instruction. gcc -O2's time on a function grows about as the
square of its size, not with the unknowns: a link of 16 intervals at order 12 with shear and axial
strain (67 unknowns, one function of 124,000 lines) took 170 s and 1.5 GB, the exact gripper (137
unknowns, four functions of 14,000) 10 s. Somewhere above 40,000 lines, at a size of gcc's own
choosing (not the lines alone), gcc drops its quadratic passes (tree PRE and the register
allocator's assignment: 80% of 155 s at 124,000 lines, under 1% at 434,636): the issue's link of 56
intervals (434,636 lines, 11.7 MB) took 82 s and 2.2 GB, a link by elements of 154,000 lines 23 s,
while a link by shooting of 124,000 lines still took 170 s. So the model predicts the quadratic regime
(an upper bound where gcc switches) up to the largest size measured in it, GCC_PREDICTED_UP_TO, and
above it only the faster regime's figures, which a function may or may not get.

Fitted to python3 -m benchmarks.export_size (2026-11-29, gcc 12.2 -O2, make with one job on a
shared 2-core machine, CPU seconds: an idle core's wall time), L a function's instructions, n its
unknowns:
  instructions  per element from its fields (below): within 10% of the generated lines (a link
                by elements up to 20% more: the largest of its strain choices is taken)
  C bytes       52,210 + sum over functions L x (20.37 + 3.53 log10(L / 10,000)): the links
                -10%..+8% (0.4 to 11.7 MB), the shipped examples -20%..+26%
  gcc seconds   0.6 + sum over functions 1.39 x (L / 10,000)^1.80 x (n / 64)^0.24: the links
                -31%..+99% (3 to 170 s; -31% a link of order 4 with 316 unknowns, else -24%; +99% a
                link by elements of degree 3), the examples -41%..+75% (within 6 s)
  gcc MB        50 + 1.5 kB x all instructions (the parsed file) + 75.3 x (L / 10,000)^1.12 x
                (n / 64)^0.48 of the largest function: the links -19%..+69%, the examples -15%..+75%
The contact task's kernel (service.export.contact_kernels) is one more function, of the
instructions its built CasADi Function counts (it is built before any C is written). Not fitted
to, the model's errors on it (gripper_ellipse_contact's finger in 1..4 intervals, 11,262 to
102,604 instructions: benchmarks.export_size --only contact): gcc seconds 0%..+86%, MB -10%..+23%,
C bytes -30%..-5%; at 148,576 (past GCC_PREDICTED_UP_TO, refused) gcc kept its quadratic passes:
111 s and 1,954 MB.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

# -- instructions of each row group (lines of its generated function) ------------------------------
# A link by shooting: intervals x order^2 x (26.9 + 13.5 per strain, shear or axial) (measured at
# order 12: 26.9 and 53.9 with both strains, within 3% over 4..56 intervals; order 8, 4: 3% over).
SHOOTING_PER_ORDER2 = 26.9
SHOOTING_PER_STRAIN = 13.5
# A link by elements, per element: (degree + 2) x degree x (1 + strains) x ELEMENTS_PER_TERM[degree]
# (the largest over the four strain choices: the others up to 20% fewer).
ELEMENTS_PER_TERM = {1: 71.0, 2: 62.0, 3: 59.0, 4: 60.0, 5: 62.0, 6: 70.0}
# A shape's coefficients are evaluated at every node (intervals x order, or x (degree + 2)), in the
# element's rows and again in the bodies' (its end point): about 5 instructions per term and node
# (measured: 4.6 for fourier_sine, 6 for a polynomial); an expression counts a term per 4 characters.
SHAPE_PER_TERM_NODE = 5.0
EXPRESSION_CHARACTERS_PER_TERM = 4
# The bodies' rows, per element (its wrenches on its two bodies, measured on the shipped examples:
# a link 1,200-1,500, a curved beam 555, a link by elements 50-550, a slider about 4,500), per load.
BODY_ROWS_PER_ELEMENT = {"link": 1500, "link_elements": 600, "curved_beam": 600, "slider": 4600, "spring": 100}
BODY_ROWS_OTHER_ELEMENT = 2000  # a family measured nowhere (a plug-in's)
BODY_ROWS_PER_LOAD = 30
OWN_ROWS_PER_UNKNOWN_OTHER = 100  # another family's own rows (a pin: 2 unknowns, 34 instructions)

# -- the C and its build, from the row groups (L instructions and n unknowns each) ------------------
C_BYTES_BASE = 52_210  # the driver, header, examples, loader, CasADi's helpers (QR, norms)
C_BYTES_PER_INSTRUCTION = 20.37
C_BYTES_PER_INSTRUCTION_DECADE = 3.53  # longer names of the work variables in a larger function
GCC_BASE_SECONDS = 0.6  # the driver, examples and linking
GCC_SECONDS, GCC_SIZE_EXPONENT, GCC_UNKNOWNS_EXPONENT = 1.39, 1.80, 0.24
GCC_BASE_MEGABYTES, GCC_PARSE_MEGABYTES_PER_INSTRUCTION = 50.0, 1.5e-3
GCC_MEGABYTES, GCC_MEGABYTES_SIZE_EXPONENT, GCC_MEGABYTES_UNKNOWNS_EXPONENT = 75.3, 1.12, 0.48
GCC_PREDICTED_UP_TO = 130_000  # the largest function measured in the quadratic regime (124,000 lines)
# above it, gcc's faster regime as measured for the link (434,636 lines: 81.5 s, 2,161 MB,
# less the base and the parsed file's share)
GCC_FAST_SECONDS_PER_INSTRUCTION = (81.5 - GCC_BASE_SECONDS) / 434_636
GCC_FAST_MEGABYTES_PER_INSTRUCTION = (
    2161.0 - GCC_BASE_MEGABYTES - GCC_PARSE_MEGABYTES_PER_INSTRUCTION * 436_180
) / 434_636

BODY_ROWS = "the free bodies' rows"


@dataclass(frozen=True)
class RowGroup:
    """One generated function: `what` (BODY_ROWS, or an element's own: "the rows of element
    'beam'"), its predicted SX instructions and the unknowns its rows belong to."""

    what: str
    instructions: int
    unknowns: int


@dataclass(frozen=True)
class ExportSize:
    """An export's predicted C: its row groups, bytes of C written, and gcc -O2's CPU seconds
    and peak memory (MB) building it with make (one job). `beyond`: its largest function is
    above GCC_PREDICTED_UP_TO, where gcc's regime is its own choice (seconds and MB are then the
    faster regime's, which it may not get)."""

    groups: tuple[RowGroup, ...]
    c_bytes: int
    gcc_seconds: float
    gcc_megabytes: float

    @property
    def largest(self) -> RowGroup:
        return max(self.groups, key=lambda g: g.instructions, default=RowGroup("nothing", 0, 0))

    @property
    def instructions(self) -> int:
        return sum(g.instructions for g in self.groups)

    @property
    def beyond(self) -> bool:
        return self.largest.instructions > GCC_PREDICTED_UP_TO


def _shape_terms(topology) -> int:
    """Terms of a link's unloaded shape evaluated per node (0: straight, arc, a curved beam's)."""
    geometry = getattr(topology, "geometry", None)
    expression = getattr(geometry, "expression", None)
    if expression:
        return max(1, len(re.sub(r"\s", "", expression)) // EXPRESSION_CHARACTERS_PER_TERM)
    return int(getattr(geometry, "terms", 0) or 0)


def _strains(topology) -> int:
    return int(bool(getattr(topology, "shear", False))) + int(bool(getattr(topology, "axial", False)))


def _shooting(topology) -> tuple[float, int]:
    """(instructions of a link by shooting's own rows, the nodes its shape is evaluated at)."""
    per_order2 = SHOOTING_PER_ORDER2 + SHOOTING_PER_STRAIN * _strains(topology)
    return topology.intervals * topology.order**2 * per_order2, topology.intervals * topology.order


def _elements(topology) -> tuple[float, int]:
    """(instructions of a link by elements' own rows, the nodes its shape is evaluated at)."""
    d = topology.degree
    per_term = ELEMENTS_PER_TERM.get(d, max(ELEMENTS_PER_TERM.values()))
    return topology.intervals * (d + 2) * d * (1 + _strains(topology)) * per_term, topology.intervals * (d + 2)


# by the family that contributes an element (ElementTopology.family): the measured ones' fields
OWN_ROWS = {"link": _shooting, "link_elements": _elements}


def own_instructions(topology) -> int:
    """Predicted SX instructions of an element's own rows (0 without unknowns of its own)."""
    if not topology.unknowns:
        return 0
    estimate = OWN_ROWS.get(topology.family)
    if estimate is None:
        return OWN_ROWS_PER_UNKNOWN_OTHER * topology.unknowns
    rows, nodes = estimate(topology)
    return round(rows + SHAPE_PER_TERM_NODE * _shape_terms(topology) * nodes)


def body_instructions(structure) -> int:
    """Predicted SX instructions of the free bodies' rows (0 when no body coordinate is free)."""
    if not structure.free:
        return 0
    total = BODY_ROWS_PER_LOAD * len(structure.loads)
    for t in structure.elements:
        total += BODY_ROWS_PER_ELEMENT.get(t.family, BODY_ROWS_OTHER_ELEMENT)
        estimate = OWN_ROWS.get(t.family)
        if estimate is not None:  # a link's end point: its shape integrated over its nodes
            total += SHAPE_PER_TERM_NODE * _shape_terms(t) * estimate(t)[1]
    return round(total)


def row_groups(structure) -> tuple[RowGroup, ...]:
    """The predicted functions of the residual and its tangent, as residual_by_rows groups them."""
    groups = [RowGroup(BODY_ROWS, body_instructions(structure), len(structure.free))] if structure.free else []
    for t in structure.elements:
        if t.unknowns:
            groups.append(RowGroup(f"the rows of element '{t.name}'", own_instructions(t), t.unknowns))
    return tuple(groups)


def function_bytes(instructions: int) -> float:
    decades = math.log10(max(instructions, 1) / 10_000)
    return instructions * (C_BYTES_PER_INSTRUCTION + C_BYTES_PER_INSTRUCTION_DECADE * decades)


def function_seconds(group: RowGroup) -> float:
    """gcc -O2's CPU seconds for one generated function."""
    if group.instructions > GCC_PREDICTED_UP_TO:
        return GCC_FAST_SECONDS_PER_INSTRUCTION * group.instructions
    size, unknowns = group.instructions / 10_000, max(group.unknowns, 1) / 64
    return GCC_SECONDS * size**GCC_SIZE_EXPONENT * unknowns**GCC_UNKNOWNS_EXPONENT


def function_megabytes(group: RowGroup) -> float:
    """gcc -O2's peak memory (MB) optimizing one generated function, beside the parsed file."""
    if group.instructions > GCC_PREDICTED_UP_TO:
        return GCC_FAST_MEGABYTES_PER_INSTRUCTION * group.instructions
    size, unknowns = group.instructions / 10_000, max(group.unknowns, 1) / 64
    return GCC_MEGABYTES * size**GCC_MEGABYTES_SIZE_EXPONENT * unknowns**GCC_MEGABYTES_UNKNOWNS_EXPONENT


def predicted_size(structure) -> ExportSize:
    """The export's predicted C and build, from a compiled mechanism's structure (mech.structure)."""
    return size_of(row_groups(structure))


def size_of(groups: tuple[RowGroup, ...]) -> ExportSize:
    """The C and build of an export of these generated functions (the row groups, and the
    contact task's kernel once it is built: service.export.contact_kernels)."""
    total = sum(g.instructions for g in groups)
    return ExportSize(
        groups=groups,
        c_bytes=round(C_BYTES_BASE + math.fsum(function_bytes(g.instructions) for g in groups)),
        gcc_seconds=GCC_BASE_SECONDS + math.fsum(function_seconds(g) for g in groups),
        gcc_megabytes=GCC_BASE_MEGABYTES
        + GCC_PARSE_MEGABYTES_PER_INSTRUCTION * total
        + max((function_megabytes(g) for g in groups), default=0.0),
    )
