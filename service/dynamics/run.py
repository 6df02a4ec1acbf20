"""A simulation of a document: its `simulate` section (with a request's fields over it)
checked, the start state, the integration, and the report in document units: times,
outputs, constraint forces, the reactions of prescribed motions, energies and the balance.

Outputs that are static by construction (a link's start wrench h, v, M_start, M_end and the
reactions, which leave out inertia) are not reported; the constraint forces are: each link
end's multipliers are the force (and moment) its end body exerts on it, exact in motion."""

from __future__ import annotations

import numpy as np
from pydantic import ValidationError

from flexmech.models import Mechanism, MechanismError
from flexmech.models.contact.elastic_pairs import check_link_dynamics
from flexmech.models.documents.simulation_spec import SimulateSpec, critical_step_factor
from flexmech.models.elements import FAMILIES
from flexmech.models.graph.residual import unknown_names
from flexmech.service.costs import Limits
from flexmech.service.dynamics.adaptive import Tolerance
from flexmech.service.dynamics.histories import Histories, read_histories, varying_values
from flexmech.service.dynamics.integrate import History, integrate
from flexmech.service.dynamics.onsets import Onsets
from flexmech.service.dynamics.schemes import Scheme, StageScheme, generalized_alpha, newmark, sdirk4
from flexmech.service.dynamics.state_map import state_map
from flexmech.service.dynamics.static_start import static_shape
from flexmech.service.dynamics.stepping import engine_of
from flexmech.service.solvers.energy import minimize_energy
from flexmech.service.solvers.reports import output_units

MAX_STEPS = Limits().max_simulation_steps  # the service's limit: the CLI and Python apply the same
STATIC_OUTPUTS = (".h", ".v", ".M_start", ".M_end")


def simulation_spec(mech: Mechanism, overrides: dict | None = None) -> SimulateSpec:
    """The document's `simulate` section with `overrides` (a request's fields) over it."""
    base = mech.document.simulate.model_dump() if mech.document.simulate is not None else {}
    merged = {**base, **{k: v for k, v in (overrides or {}).items() if v is not None}}
    try:
        spec = SimulateSpec.model_validate(merged)
    except ValidationError as exc:
        error = exc.errors()[0]
        where = "/".join(str(part) for part in error["loc"])
        raise MechanismError(
            f"/simulate/{where}" if where else "/simulate", error["msg"].removeprefix("Value error, ")
        ) from None
    if spec.until is None:
        raise MechanismError("/simulate/until", "give the end time `until` (s), in the document or the request")
    return spec


def scheme_of(spec: SimulateSpec) -> Scheme | StageScheme:
    if spec.scheme == "newmark":
        return newmark(spec.a1, spec.a2 / 2)
    if spec.scheme == "sdirk4":
        return sdirk4()
    return generalized_alpha(spec.rho_inf)


def check_stage_scheme(mech: Mechanism, spec: SimulateSpec, histories: Histories) -> None:
    """What sdirk4 does not do yet: damped contacts (whose onsets the generalized-alpha steps
    locate)."""
    if spec.scheme != "sdirk4":
        return
    if Onsets(mech.structure, histories.moving):
        raise MechanismError(
            "/simulate/scheme", "sdirk4 does not step onto damped contacts' onsets: use generalized_alpha"
        )


def simulated(mech: Mechanism) -> Mechanism:
    """The mechanism, its reports read from the graphs of outputs alone: a simulation's states
    come from the element kernels, so the residual form is never built for it."""
    mech.graphs.prefer_reporting()
    return mech


def check_masses(mech: Mechanism) -> None:
    """Every element link dynamics integrates carries mass (a link by shooting or a massless one
    has no dynamics of its own): each family says (its check_simulated)."""
    for t in mech.structure.elements:
        check = getattr(FAMILIES.of(t), "check_simulated", None)
        if check is not None:
            check(t)


def tolerance_of(spec: SimulateSpec, max_steps: int = MAX_STEPS) -> Tolerance | None:
    """The adaptive steps' tolerance and limits, or None for fixed steps."""
    if not spec.adaptive:
        return None
    return Tolerance(
        spec.tolerance,
        spec.max_step if spec.max_step is not None else float("inf"),
        spec.min_step,
        step_limit(spec, max_steps),
    )


def step_limit(spec: SimulateSpec, max_steps: int) -> int:
    """The run's step limit: the request's, capped by the service's."""
    return min(spec.max_steps, max_steps) if spec.max_steps is not None else max_steps


def check_steps(spec: SimulateSpec, max_steps: int) -> int:
    """The run's steps; refused over the limit, which counts a stage scheme's implicit stages
    (each costs about one generalized-alpha step)."""
    steps = int(round(spec.until / spec.step))
    limit = step_limit(spec, max_steps)
    if steps < 1:
        raise MechanismError("/simulate/step", f"the step {spec.step:g} s is longer than the run ({spec.until:g} s)")
    stages = sdirk4().stages if spec.scheme == "sdirk4" else 1
    if steps * stages > limit and not spec.adaptive:
        solves = f" ({steps * stages} implicit stage solves)" if stages > 1 else ""
        raise MechanismError(
            "/simulate/step",
            f"the run needs {steps} steps of {spec.step:g} s{solves}, over the limit of "
            f"{limit}: take a longer step or a shorter run",
        )
    return steps


def check_scheme(mech: Mechanism, spec: SimulateSpec, x0: np.ndarray | None = None) -> None:
    """A conditionally stable Newmark pair (a2 < a1) is refused with its critical step, from the
    mechanism's highest natural frequency at the start (x0; None: the undeformed state)."""
    if spec.scheme != "newmark" or spec.a2 >= spec.a1 - 1e-12:
        return  # nothing built for every other run
    from flexmech.service.dynamics.modes import highest_frequency

    if x0 is None:
        x0 = np.zeros(len(mech.graphs.energy_form.unknowns))

    factor = critical_step_factor(spec.a1, spec.a2 / 2)
    omega = highest_frequency(mech.structure, mech.p(), x0)
    critical = f"{factor / omega:.3g} s" if omega > 0 else "unbounded (no stiffness at the start)"
    raise MechanismError(
        "/simulate/a2",
        f"Newmark a1 = {spec.a1:g}, a2 = {spec.a2:g} is only conditionally stable "
        f"(unconditional stability needs a2 >= a1): its critical step is {factor:.4g} / omega_max "
        f"= {critical} for this mechanism (omega_max = {omega:.4g} rad/s); raise a2 to at least "
        f"{spec.a1:g}",
    )


def start_shape(mech: Mechanism, spec: SimulateSpec, histories: Histories | None = None) -> tuple[np.ndarray, str]:
    """The energy form's x at t = 0, and how it was found: a static start by Newton on the run's
    own element kernels (service.dynamics.static_start), else by minimizing the energy."""
    if spec.start != "equilibrium":
        return np.zeros(len(mech.graphs.energy_form.unknowns)), "from rest, undeformed"
    note = "from rest, in static equilibrium under the document's values"
    histories = histories or read_histories(mech, spec.histories, spec.until, "/simulate/histories")
    x = static_shape(engine_of(mech.structure, scheme_of(spec), histories), mech.p())
    if x is not None:
        return x, note
    static = minimize_energy(mech)
    if static.status != "converged":
        raise MechanismError("/simulate/start", f"the static start did not converge ({static.status})")
    return mech.graphs.energy_form.x_of_state(static.z), note


def run_simulation(
    mech: Mechanism, spec: SimulateSpec, stop=None, progress=None, max_steps: int = MAX_STEPS
) -> tuple[History, dict]:
    """(the raw history, the report). With an accuracy target, of the run that meets it
    (service.dynamics.accuracy)."""
    if spec.accuracy is not None:
        from flexmech.service.dynamics.accuracy import run_to_accuracy  # it calls back here, per run

        def run(m: Mechanism, s: SimulateSpec) -> tuple[History, dict]:
            return run_simulation(m, s, stop, progress, max_steps)

        return run_to_accuracy(mech, spec, run, stop)
    simulated(mech)
    check_masses(mech)
    check_link_dynamics(mech.document)  # its contact pairs: elastic, frictionless
    check_steps(spec, max_steps)
    histories = read_histories(mech, spec.histories, spec.until, "/simulate/histories")
    x0, start_note = start_shape(mech, spec, histories)
    check_scheme(mech, spec, x0)
    check_stage_scheme(mech, spec, histories)
    n, p = len(x0), mech.p()
    history = integrate(
        mech.structure,
        p,
        x0,
        np.zeros(n),
        spec.until,
        spec.step,
        scheme_of(spec),
        damping=spec.damping,
        every=spec.every,
        stop=stop,
        histories=histories,
        progress=progress,
        adaptive=tolerance_of(spec, max_steps),
    )
    return history, report(mech, spec, history, histories, start_note)


def records(mech: Mechanism, spec: SimulateSpec, history: History, histories) -> dict:
    """The kept states of a history in document units: times, outputs, constraint forces,
    the prescribed motions' reactions, and the energies and works (from t = 0)."""
    form = state_map(mech.structure)
    names, kinds = mech.graphs.output_names, mech.graphs.output_kinds
    wanted = wanted_outputs(mech, spec)
    if history.times:
        states = np.column_stack([form.to_state(x, lam) for x, lam in zip(history.x, history.lam)])
        values = np.asarray(mech.graphs.outputs.map(len(history.times))(states, np.column_stack(history.p)))
    else:
        values = np.zeros((len(names), 0))
    outputs = {
        name: (values[names.index(name)] / mech.nd_per_doc(kinds[names.index(name)])).tolist() for name in wanted
    }
    _damped_normal_forces(mech, history, histories, outputs)
    state_names = unknown_names(mech.structure)
    forces, series_units = {}, {}
    multipliers = np.array(history.lam).reshape(len(history.lam), -1)
    for j, index in enumerate(form.multipliers_in_state):
        name, kind = state_names[index]
        forces[name] = (multipliers[:, j] / mech.nd_per_doc(kind)).tolist()
        series_units[name] = mech.doc_unit(kind)
    energy = 1 / mech.nd_per_doc("force") / mech.nd_per_doc("length")
    motion_forces = {}
    for k, index in enumerate(histories.moving):
        pointer = mech.parameters[index].pointer
        kind = "moment" if pointer.endswith("/rotation") else "force"
        scale = mech.nd_per_doc(kind)
        motion_forces[pointer] = [float(q[k]) / scale for q in history.motion_forces]
        series_units[pointer] = mech.doc_unit(kind)
    kept = {
        "times": list(history.times),
        "outputs": outputs,
        "constraint_forces": forces,
        "motion_forces": motion_forces,
        "series_units": series_units,
        "steps": history.steps,
        "varying": varying_values(mech, histories, history.p),
        "energies": {
            "kinetic": [e * energy for e in history.kinetic],
            "potential": [e * energy for e in history.potential],
            "input_work": [e * energy for e in history.input_work],
            "damping_work": [e * energy for e in history.damping_work],
            "friction_work": [e * energy for e in history.friction_work],
            "contact_damping_work": [e * energy for e in history.contact_damping_work],
        },
    }
    if spec.shapes:
        kept["shapes"] = shapes_of(mech, states, history.p) if history.times else []
    return kept


def _damped_normal_forces(mech: Mechanism, history: History, histories, outputs: dict) -> None:
    """A damped contact pair's normal force is its elastic part and its damping, which reads the
    velocities: the outputs of the states alone give the first; this puts in the whole."""
    onsets = Onsets(mech.structure, histories.moving)  # a run's own: CasADi Functions are not shared across threads
    wanted = [name for name in onsets.names if f"contacts.{name}.normal_force" in outputs]
    if not wanted or not history.times:
        return
    n = len(mech.structure.free)
    x, v = (np.column_stack([q[:n] for q in rows]) for rows in (history.x, history.v))
    rates = histories.at_times(mech.p(), np.asarray(history.times))[1]
    forces = onsets.normal_forces(x, v, np.column_stack(history.p), rates)
    for name in wanted:
        outputs[f"contacts.{name}.normal_force"] = forces[name].tolist()


def shapes_of(mech: Mechanism, states: np.ndarray, parameters: list) -> list[dict]:
    """Per kept state, every drawn element's deformed centre line [[x...], [y...]] (document
    length unit)."""
    scale = 1 / mech.nd_per_doc("length")
    out = []
    for k in range(states.shape[1]):
        line = np.asarray(mech.graphs.shapes(states[:, k], parameters[k])[0]) * scale
        out.append(
            {name: line[:, first : first + count].tolist() for name, first, count, _, _ in mech.graphs.shape_segments}
        )
    return out


def kept_state_numbers(mech: Mechanism, spec: SimulateSpec) -> int:
    """The numbers records() keeps of one state: its time, the wanted outputs, the constraint
    forces, the prescribed motions' reactions and varying fields, six energies and (with shapes)
    every drawn centre-line point."""
    numbers = 7 + len(wanted_outputs(mech, spec)) + len(mech.graphs.energy_form.equality_names)
    numbers += 2 * len(spec.histories)  # a varying field's value, a prescribed motion's reaction
    if spec.shapes:
        numbers += 2 * sum(count for _, _, count, _, _ in mech.graphs.shape_segments)
    return numbers


def wanted_outputs(mech: Mechanism, spec: SimulateSpec) -> list[str]:
    names = mech.graphs.output_names
    if spec.outputs is None:
        return [name for name in names if not name.endswith(STATIC_OUTPUTS) and not name.startswith("reactions.")]
    for k, name in enumerate(spec.outputs):
        if name not in names:
            raise MechanismError(
                f"/simulate/outputs/{k}", f"unknown output '{name}' (outputs: {', '.join(names[:12])}, ...)"
            )
    return list(spec.outputs)


def with_balance(energies: dict) -> tuple[dict, float | None]:
    """The energies with their balance T + V - W_inputs + W_damping - W_friction - W_contact_damping
    (less its start; the contacts' works are <= 0), and the largest |balance| relative to the
    largest energy seen."""
    T, V, W, D = (np.array(energies[k]) for k in ("kinetic", "potential", "input_work", "damping_work"))
    if not len(T):
        return {**energies, "balance": []}, None
    balance = T + V - W + D
    for key in ("friction_work", "contact_damping_work"):  # none in windows stored before them
        work = np.array(energies.get(key, []))
        balance = balance - (work if len(work) == len(T) else 0.0)
    balance = balance - balance[0]
    size = max(np.abs(T).max(), np.abs(V - V[0]).max(), np.abs(W).max(), 1e-300)
    return {**energies, "balance": balance.tolist()}, float(np.abs(balance).max() / size)


def units(mech: Mechanism) -> dict:
    moment = f"{mech.doc_unit('force')}*{mech.doc_unit('length')}"
    return {
        "time": "s",
        "force": mech.doc_unit("force"),
        "length": mech.doc_unit("length"),
        "moment": moment,
        "energy": moment,
        "angle": mech.doc_unit("angle"),
    }


def report(mech: Mechanism, spec: SimulateSpec, history: History, histories, start_note: str) -> dict:
    kept = records(mech, spec, history, histories)
    energies, error = with_balance(kept.pop("energies"))
    every = output_units(mech)
    return {
        "analysis": "simulate",
        "name": mech.document.name,
        "status": history.status,
        "message": history.message,
        "time_reached": history.resume.time if history.resume is not None else 0.0,
        "steps": history.steps,
        "iterations": history.iterations,
        "rescued_steps": history.newton_iterations,
        "seconds": history.seconds,
        "kernels": history.kernels,
        "start": start_note,
        "scheme": scheme_summary(spec),
        "step": spec.step,
        "adaptive": {"tolerance": spec.tolerance, "max_step": spec.max_step} if spec.adaptive else None,
        "damping": spec.damping,
        **kept,
        "energies": energies,
        "energy_balance_error": error,
        "units": units(mech),
        "output_units": {name: every[name] for name in kept["outputs"]},
    }


def scheme_summary(spec: SimulateSpec) -> dict:
    if spec.scheme == "newmark":
        return {"name": "newmark", "a1": spec.a1, "a2": spec.a2}
    if spec.scheme == "sdirk4":
        return {"name": "sdirk4", "order": 4, "stages": sdirk4().stages}
    return {"name": "generalized_alpha", "rho_inf": spec.rho_inf}
