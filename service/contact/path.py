"""Quasi-static contact paths: numeric fields (object poses, finger rotations, ...) changed
together, state after state, each solved from the one before (IPOPT warm start, following one
branch), friction sliding against the motion from the previous state."""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from flexmech.models import Mechanism, MechanismError
from flexmech.models.contact.schema import PathParameter
from flexmech.service.contact.drawing import state_drawing
from flexmech.service.contact.problem import ContactProblem
from flexmech.service.contact.report import friction_coefficients, pairs_report
from flexmech.service.contact.solve import ContactOptions, ContactState, empty_mode, solve_state
from flexmech.service.jobs.grids import Ranged, parameter_values, value_count


@dataclass(frozen=True)
class PathFields:
    pointers: tuple[str, ...]
    values: tuple[tuple[float, ...], ...]  # per field, its values along the path (document units)

    @property
    def states(self) -> int:
        return len(self.values[0])

    def at(self, index: int) -> list[float]:
        return [v[index] for v in self.values]


def path_count(parameters: Sequence[Ranged], pointer: str = "/path") -> int:
    """How many states a path has, checked before any value is made (all fields change
    together, so each gives as many values)."""
    counts = [value_count(p, f"{pointer}/{k}") for k, p in enumerate(parameters)]
    if len(set(counts)) > 1:
        raise MechanismError(
            pointer,
            "every field of a path changes together: give each as many values "
            f"(got {', '.join(str(c) for c in counts)})",
        )
    return counts[0]


def path_fields(mech: Mechanism, given: Sequence[Ranged | Mapping[str, Any]], pointer: str = "/path") -> PathFields:
    """The fields' values along the path, checked (a mapping is read as the document's
    PathParameter first)."""
    parameters = [p if not isinstance(p, Mapping) else PathParameter.model_validate(p) for p in given]
    path_count(parameters, pointer)
    pointers, values = [], []
    for k, parameter in enumerate(parameters):
        try:
            mech.parameter_index(parameter.path)
        except MechanismError as exc:
            raise MechanismError(f"{pointer}/{k}/path", exc.problem) from None
        these = parameter_values(parameter, f"{pointer}/{k}")
        for value in these:
            mech.checked_si(parameter.path, value, f"{pointer}/{k}")
        pointers.append(parameter.path)
        values.append(tuple(these))
    if len(set(pointers)) != len(pointers):
        raise MechanismError(pointer, "a field is listed twice")
    return PathFields(tuple(pointers), tuple(values))


def parameters_at(mech: Mechanism, fields: PathFields, index: int) -> np.ndarray:
    p = mech.p()
    for pointer, value in zip(fields.pointers, fields.at(index)):
        k = mech.parameter_index(pointer)
        p[k] = value * mech.nd_per_doc(mech.parameters[k].kind)
    return p


def follow(
    mech: Mechanism,
    problem: ContactProblem,
    fields: PathFields,
    indices: list[int],
    previous: ContactState | None,
    options: ContactOptions,
    stop: Callable[[], bool] = lambda: False,
) -> Iterator[tuple[int, ContactState]]:
    """The states at `indices` in order, each from the last converged one."""
    for index in indices:
        if stop():
            return
        p = parameters_at(mech, fields, index)
        state = solve_state(problem, p, friction_coefficients(mech, problem, p), previous, options)
        if state.converged:
            previous = state
        yield index, state


def resumed_state(problem: ContactProblem, p: np.ndarray, stored: dict) -> ContactState:
    """A stored state (its v and friction directions) to go on from."""
    return ContactState(
        "converged",
        p,
        np.asarray(stored["v"], dtype=float),
        empty_mode(problem),
        [],
        np.asarray(stored["sigma"], dtype=float),
        0,
        0.0,
    )


def state_record(
    mech: Mechanism, problem: ContactProblem, state: ContactState, values: list[float], outputs: list[str]
) -> dict:
    """A state as stored: its values, status, pairs, chosen outputs and its drawing (document
    units), and what a resumed path needs to go on from it."""
    mode = state.mode
    y = np.asarray(problem.outputs(state.v, state.p, mode.phi, mode.stick, mode.weights), dtype=float).ravel()
    open_pairs = {
        pair.name for pair, state_of in zip(problem.structure.contacts.pairs, state.pair_states) if state_of == "open"
    }
    chosen = {}
    for name in outputs:
        k = problem.output_names.index(name)
        chosen[name] = y[k] / mech.nd_per_doc(problem.output_kinds[k])
        pair = name.removeprefix("contacts.").rpartition(".")[0] if name.startswith("contacts.") else None
        if pair in open_pairs:  # no contact: no force, no point (not rounding noise)
            chosen[name] = 0.0 if problem.output_kinds[k] == "force" else None
    return {
        "values": values,
        "status": state.status,
        "message": state.message,
        "iterations": state.iterations,
        "seconds": state.seconds,
        "pairs": pairs_report(mech, problem, state),
        "outputs": chosen,
        "drawing": state_drawing(mech, problem, state),
        "state": {"v": state.v.tolist(), "sigma": state.sigma.tolist()},
    }


def default_outputs(problem: ContactProblem) -> list[str]:
    return [name for name in problem.output_names if name.startswith("contacts.")]
