"""The toleranced fields of a document (models.documents.tolerances) checked against its compiled
mechanism, and the scatter they make: independent standardized sources (one per field, or one per
group of correlated fields), each field moving by its own width times its source's draw.

A source's draw xi is N(0, 1) for a normal field (the field moves by sigma xi) and U(-1, 1) for a
uniform one (plus_minus xi; its standard deviation is plus_minus / sqrt(3)). Samples are drawn
for a whole run at once from one seed, so any split of the samples into tasks (a process pool,
a Dask cluster) evaluates the same samples."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from flexmech.models import Mechanism, MechanismError
from flexmech.models.documents.tolerances import TolerancesSpec
from flexmech.models.units import quantity_to_si

NEGATIVE_PROBABILITY = 1e-6  # the most a scatter may put a positive field at or below zero
_RANGES = {"positive": (0.0, math.inf), "nonnegative": (0.0, math.inf), "arc_angle": (0.0, 2 * math.pi)}


def field_pointer(path: str) -> str:
    """The pointer of a toleranced field's entry: /tolerances/fields/<path, escaped>."""
    return "/tolerances/fields/" + path.replace("~", "~0").replace("/", "~1")


@dataclass(frozen=True)
class Toleranced:
    """One toleranced field: its parameter slot, kind and document unit, its distribution and
    width (document units), and the independent source it moves with."""

    path: str
    slot: int
    kind: str
    unit: str
    distribution: str  # normal | uniform
    width: float  # sigma or plus_minus, document units
    source: int

    @property
    def std(self) -> float:
        """Standard deviation, document units."""
        return self.width if self.distribution == "normal" else self.width / math.sqrt(3.0)


@dataclass(frozen=True)
class Scatter:
    fields: tuple[Toleranced, ...]
    sources: tuple[str, ...]  # each independent source named by its leading field
    source_kinds: tuple[str, ...]  # normal | uniform

    @property
    def paths(self) -> list[str]:
        return [f.path for f in self.fields]

    @property
    def slots(self) -> list[int]:
        return [f.slot for f in self.fields]

    def loadings(self) -> np.ndarray:
        """(fields x sources): a field's move per unit of its source's standard deviation
        (document units): its own standard deviation in its source's column."""
        L = np.zeros((len(self.fields), len(self.sources)))
        for i, f in enumerate(self.fields):
            L[i, f.source] = f.std
        return L

    def draws(self, samples: int, seed: int) -> np.ndarray:
        """(samples x sources) standardized draws: N(0, 1) for normal sources, U(-1, 1) for
        uniform ones; the same for a seed however the samples are split later."""
        rng = np.random.default_rng(seed)
        normal = rng.standard_normal((samples, len(self.sources)))
        uniform = rng.uniform(-1.0, 1.0, (samples, len(self.sources)))
        return np.where(np.array(self.source_kinds) == "normal", normal, uniform)

    def deviations(self, draws: np.ndarray) -> np.ndarray:
        """(samples x fields) deviations from the document's values, document units."""
        columns = [f.source for f in self.fields]
        return draws[:, columns] * np.array([f.width for f in self.fields])[None, :]

    def nondimensional(self, mech: Mechanism, deviations: np.ndarray) -> np.ndarray:
        """Deviations in the mechanism's nondimensional parameters (samples x fields)."""
        return deviations * np.array([mech.nd_per_doc(f.kind) for f in self.fields])[None, :]


def resolve_scatter(mech: Mechanism, spec: TolerancesSpec) -> Scatter:
    """The scatter of `spec` on `mech`, every problem a MechanismError at its entry
    (/tolerances/fields/<escaped pointer>/...): a pointer that is not a numeric field, a width
    that is not a positive quantity of the field's kind, a correlation with a field that is not
    toleranced (or of the other kind of scatter), a scatter that puts a positive field (a width,
    a radius, a modulus) at or below zero with a probability above NEGATIVE_PROBABILITY."""
    leaders = _leaders(spec)
    sources = [path for path in spec.fields if leaders[path] == path]
    fields = []
    for path, distribution in spec.fields.items():
        where = field_pointer(path)
        try:
            slot = mech.parameter_index(path)
        except MechanismError as exc:
            raise MechanismError(where, f"'{path}' is {exc.problem}") from None
        parameter = mech.parameters[slot]
        unit = mech.doc_unit(parameter.kind)
        name = "sigma" if distribution.kind == "normal" else "plus_minus"
        width = quantity_to_si(distribution.width, parameter.kind, unit, f"{where}/{name}") / mech.doc_factor(
            parameter.kind
        )
        if not width > 0:
            raise MechanismError(f"{where}/{name}", f"must be positive, got {distribution.width}")
        field = Toleranced(path, slot, parameter.kind, unit, distribution.kind, width, sources.index(leaders[path]))
        _check_range(mech, field, parameter.check, f"{where}/{name}")
        fields.append(field)
    kinds = tuple(spec.fields[path].kind for path in sources)
    return Scatter(tuple(fields), tuple(sources), kinds)


def _leaders(spec: TolerancesSpec) -> dict[str, str]:
    """Each field's leading field: itself, or the toleranced field it is correlated with (one
    level: a leader is not correlated with another)."""
    leaders = {}
    for path, distribution in spec.fields.items():
        other = distribution.correlated_with
        where = field_pointer(path) + "/correlated_with"
        if other is None:
            leaders[path] = path
            continue
        if other == path:
            raise MechanismError(where, "a field is correlated with itself already: name another toleranced field")
        if other not in spec.fields:
            raise MechanismError(where, f"'{other}' has no tolerance: correlate with a field of tolerances.fields")
        if spec.fields[other].correlated_with is not None:
            raise MechanismError(
                where, f"'{other}' moves with '{spec.fields[other].correlated_with}': correlate with that field"
            )
        if spec.fields[other].kind != distribution.kind:
            raise MechanismError(
                where,
                f"'{other}' has a {spec.fields[other].kind} scatter and this one a {distribution.kind}: "
                "fields that move together need the same kind",
            )
        leaders[path] = other
    return leaders


def _check_range(mech: Mechanism, field: Toleranced, check: str | None, where: str) -> None:
    """A positive field (or an arc angle) must stay in its range but for a negligible probability."""
    if check not in _RANGES:
        return
    factor = mech.doc_factor(field.kind)
    low, high = (bound / factor for bound in _RANGES[check])
    value = mech.value(field.path)
    if field.distribution == "uniform":
        outside = 1.0 if (value - field.width <= low or value + field.width >= high) else 0.0
    else:
        outside = _normal_tail((value - low) / field.width) + _normal_tail((high - value) / field.width)
    if outside > NEGATIVE_PROBABILITY:
        if field.distribution == "uniform":
            raise MechanismError(
                where,
                f"plus_minus {field.width:g} {field.unit} takes {field.path} ({value:g} {field.unit}) out of its "
                f"range ({_range_text(check)})",
            )
        raise MechanismError(
            where,
            f"sigma {field.width:g} {field.unit} takes {field.path} ({value:g} {field.unit}) out of its range "
            f"({_range_text(check)}) with probability {outside:.2g}; at most {NEGATIVE_PROBABILITY:g} is allowed",
        )


def _normal_tail(z: float) -> float:
    """P(N(0, 1) > z)."""
    return 0.0 if math.isinf(z) else 0.5 * math.erfc(z / math.sqrt(2.0))


def _range_text(check: str) -> str:
    return {"positive": "above zero", "nonnegative": "not below zero", "arc_angle": "0 to 360 deg"}[check]
