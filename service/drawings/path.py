"""A quasi-static path drawn state by state, for the workbench's animation of a sweep: the
field takes its values in order, each equilibrium solved by Newton from the one before (as
a continuation sweep solves them), and each state becomes a frame (service.drawings.drawing)."""

from __future__ import annotations

import numpy as np

from flexmech.models import Mechanism, MechanismError
from flexmech.service.deadline import ends_after, passed
from flexmech.service.drawings.drawing import state_frame
from flexmech.service.solvers.equilibrium import newton
from flexmech.service.solvers.newton import NewtonOptions

MAX_FRAMES = 400


def path_frames(mech: Mechanism, pointer: str, values: list[float], options: NewtonOptions) -> list[dict]:
    """One frame per value: {value, status, elements, poses}. A state that does not converge
    is a frame with its status (and the last iterate), and the next starts from the last
    converged state. The options' time limit bounds the whole path: the frames drawn by then
    (at least the first) are returned."""
    if len(values) > MAX_FRAMES:
        raise MechanismError("/path/values", f"{len(values)} states: at most {MAX_FRAMES} are drawn")
    try:
        mech.parameter_index(pointer)
    except MechanismError as exc:
        raise MechanismError("/path/path", exc.problem) from None
    guess = np.zeros(mech.structure.n_unknowns)
    end = ends_after(options.time_limit)
    frames = []
    for value in values:
        if frames and passed(end):
            break
        at = mech.with_values({pointer: value})
        result = newton(at, at.p(), guess, options)
        if result.converged:
            guess = result.z
        frames.append({"value": value, "status": result.status, **state_frame(at, result.z, at.p(), result.outputs())})
    return frames
