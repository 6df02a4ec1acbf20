"""The numbers of an impact model: every value the graphs use is a named parameter (SI),
so one built (and compiled) model serves every variation of masses, radii, stiffnesses and
coefficients, as the parametric study needs."""

from __future__ import annotations

import casadi as ca
import numpy as np

from flexmech.models.documents.document import MechanismDocument
from flexmech.models.errors import MechanismError
from flexmech.models.units import document_unit, quantity_to_si


class ParameterBook:
    def __init__(self, document: MechanismDocument):
        self.document = document
        self.pointers: list[str] = []
        self.values: list[float] = []
        self._symbols: list[ca.SX] = []
        self._derived: list[tuple[ca.SX, ca.SX]] = []  # (symbol, expression of the numbers)
        self._computed: list[tuple[ca.SX, ca.Function, ca.SX]] = []  # (symbol, Function, its input in the numbers)
        self.units: dict[str, tuple[str, float]] = {}  # pointer -> (its unit in the document, SI per that unit)

    def si(self, value, kind: str, pointer: str) -> float:
        """A document number (or quantity string) of `kind` in SI."""
        return quantity_to_si(value, kind, document_unit(self.document.units, kind), pointer)

    def add(self, pointer: str, value: float, check: str | None = None, unit: tuple[str, float] = ("SI", 1.0)) -> ca.SX:
        """Register an SI value under its document pointer; its symbol. `unit`: the number's
        unit in the document and its SI value (sensitivities are reported per that unit)."""
        self.units.setdefault(pointer, unit)
        if not np.isfinite(value):
            raise MechanismError(pointer, "must be a finite number")
        if check == "positive" and value <= 0:
            raise MechanismError(pointer, f"must be positive, got {value:g}")
        if check == "nonnegative" and value < 0:
            raise MechanismError(pointer, f"must not be negative, got {value:g}")
        if pointer in self.pointers:
            return self._symbols[self.pointers.index(pointer)]
        symbol = ca.SX.sym(pointer)
        self.pointers.append(pointer)
        self.values.append(float(value))
        self._symbols.append(symbol)
        return symbol

    def number(self, pointer: str, value, kind: str, check: str | None = None) -> ca.SX:
        unit = document_unit(self.document.units, kind) if kind != "dimensionless" else "1"
        return self.add(pointer, self.si(value, kind, pointer), check, (unit, self.si(1.0, kind, pointer)))

    def vector(self, pointer: str, value, kind: str) -> ca.SX:
        return ca.vertcat(*[self.number(f"{pointer}/{k}", v, kind) for k, v in enumerate(value)])

    def hoist(self, expression: ca.SX) -> ca.SX:
        """A stand-in for an expression of the numbers alone (a stiffness matrix, a drawn point
        in body axes): computed once per run, not at every step."""
        if self._derived:  # in the numbers alone, so that p evaluates in one pass
            expression = ca.substitute(
                expression,
                ca.vertcat(*[ca.vec(s) for s, _ in self._derived]),
                ca.vertcat(*[ca.vec(e) for _, e in self._derived]),
            )
        symbol = ca.SX.sym(f"derived{len(self._derived)}", expression.shape)
        self._derived.append((symbol, expression))
        return symbol

    def computed(self, function: ca.Function, inputs: ca.SX, name: str) -> ca.SX:
        """A stand-in for `function(inputs)`, a Function of one input and one output that SX
        cannot hold (a linear solve, a root): evaluated once per run, differentiated exactly
        (parameter_jacobian), its input an expression of the numbers."""
        out = function.sparsity_out(0)
        symbol = ca.SX.sym(name, out.size1(), out.size2())
        self._computed.append((symbol, function, inputs))
        return symbol

    def value(self, pointer: str) -> float:
        return self.values[self.pointers.index(pointer)]

    @property
    def symbols(self) -> ca.SX:
        """The numbers, then the hoisted expressions, then the computed blocks: the graphs'
        parameter vector p."""
        base = (
            list(self._symbols)
            + [ca.vec(symbol) for symbol, _ in self._derived]
            + [ca.vec(symbol) for symbol, _, _ in self._computed]
        )
        return ca.vertcat(*base) if base else ca.SX(0, 1)

    def _beyond_numbers(self) -> ca.Function | None:
        """numbers (MX) -> the hoisted expressions and the computed blocks, or None if none."""
        if not self._derived and not self._computed:
            return None
        numbers = ca.vertcat(*self._symbols)
        x = ca.MX.sym("numbers", numbers.numel())
        computed = [function(ca.Function("inputs", [numbers], [inputs])(x)) for _, function, inputs in self._computed]
        # hoisted expressions may hold computed blocks (a point where a computed end lies)
        hoisted = ca.Function(
            "hoisted",
            [numbers, *[symbol for symbol, _, _ in self._computed]],
            [ca.vertcat(*[ca.vec(e) for _, e in self._derived])],
        )
        return ca.Function("beyond_numbers", [x], [ca.vertcat(hoisted(x, *computed), *[ca.vec(c) for c in computed])])

    def parameter_vector(self, values=None) -> np.ndarray:
        """p for the numbers `values` (default: the document's), hoisted expressions and
        computed blocks evaluated."""
        values = np.asarray(self.values if values is None else values, dtype=float)
        beyond = self._beyond_numbers()
        if beyond is None:
            return values
        return np.concatenate([values, np.asarray(beyond(values)).ravel()])

    def parameter_jacobian(self, values=None) -> np.ndarray:
        """d p / d numbers at the numbers `values` (default: the document's): the identity over
        the numbers, and the derivatives of what is computed from them below it."""
        values = np.asarray(self.values if values is None else values, dtype=float)
        beyond = self._beyond_numbers()
        if beyond is None:
            return np.eye(len(values))
        x = ca.MX.sym("numbers", len(values))
        jacobian = ca.Function("dp", [x], [ca.jacobian(ca.vertcat(x, beyond(x)), x)])
        return np.asarray(jacobian(values))
