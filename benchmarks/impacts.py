"""Speed of seed 004's impact models against peers, side by side in one run, on 1 s of
scenario 6.3 (the CSFH from q0 = [0.01, 0.01, 0]; examples/csfh.json), end to end: the
model built, the steps, the report (energies, events, impacts, the kept states) and its
JSON, per simulated second.

  flexmech Moreau-Jean at h = 1e-5 with Coulomb friction, against Siconos (Debian's
      python3-siconos, run by /usr/bin/python3: benchmarks/siconos_peer.py), Moreau-Jean at
      h = 1e-5 on the same rigid-impact model: the same flexure (constant stiffness),
      gravity, pin in hole, e_N = 0.9 and one Coulomb coefficient mu (Siconos has one, so
      both take f_a = f_d = 0.055). Siconos' whole run (its model built, stepped, its
      impacts and states collected) and its stepping alone are both printed.
  flexmech event-driven: Lankarani-Nikravesh (K cylinders of Table 2) with Ambrosio
      friction, Dormand-Prince 5(4) at a local error of 1e-10, contact and slip events
      located; against scipy's solve_ivp (RK45, the same Dormand-Prince pair, the same
      tolerances and longest step, its own event location) on the same compliant model: the
      same right-hand side (benchmarks/scipy_events_peer.py), flags flipped at each event.

Cold: in an empty kernel cache, the first run (the step chunk on CasADi's virtual machine;
a server's build queue compiles it meanwhile), then the compile, timed apart. Warm: the
chunk compiled, the best of three runs. Both sides print the same-motion checks: the first
impacts, q at 0.5 s and 1 s, and the mechanical energy (T + elastic + gravity) at 1 s, each
side's state evaluated by the same energy function.

Also printed, as references for others: scenario 6.3 with Moreau at h = 1e-5, f_a = 0.11,
f_d = 0.055: the first three impacts and q at 0.5 s; scenario 6.1 with Moreau: the first
impact's impulse and y at 1 s; the Table 2 stiffnesses.

    apt-get install python3-siconos
    python3 -m benchmarks.impacts
"""

from __future__ import annotations

import copy
import json
import math
import os
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

import casadi as ca
import numpy as np

from flexmech.models.beams.curved_beam_closed_form import stiffness
from flexmech.models.contact.laws.penalty import hertz_stiffness
from flexmech.models.documents.document import MechanismDocument
from flexmech.models.documents.simulation_spec import SimulateSpec
from flexmech.service.impacts.run import model_of, run_impacts

ROOT = Path(__file__).resolve().parents[1]
PEER = ["/usr/bin/python3", str(ROOT / "benchmarks" / "siconos_peer.py")]
UNTIL = 1.0


def document(name: str, **simulate) -> dict:
    """An example with `simulate` fields over it; for the moreau scheme, the laws it takes
    (restitution impulses with the example's coefficient, Coulomb's friction)."""
    doc = json.loads((ROOT / "examples" / name).read_text())
    doc["simulate"].update(simulate)
    if simulate.get("scheme") == "moreau":
        pair = doc["contacts"]["pairs"]["conjugate"]
        pair["normal"] = {"law": "restitution", "restitution": pair["normal"]["restitution"]}
        pair["friction"] = {
            "law": "coulomb",
            "adherence": pair["friction"]["adherence"],
            "sliding": pair["friction"]["sliding"],
        }
    return doc


def coulomb(doc: dict, adherence: float, sliding: float) -> dict:
    doc = copy.deepcopy(doc)
    doc["contacts"]["pairs"]["conjugate"]["friction"] = {"law": "coulomb", "adherence": adherence, "sliding": sliding}
    return doc


def end_to_end(doc: dict) -> tuple[dict, float, int]:
    """(report, seconds of the whole run: parse, model, steps, report, JSON; the JSON's bytes)."""
    began = time.perf_counter()
    parsed = MechanismDocument.model_validate(doc)
    _, report = run_impacts(parsed, SimulateSpec.model_validate(doc["simulate"]))
    size = len(json.dumps(report))
    return report, time.perf_counter() - began, size


def run(doc: dict, repeat: int = 3) -> tuple[dict, float, int]:
    """(report, best seconds end to end, JSON bytes)."""
    best, report, size = math.inf, None, 0
    for _ in range(repeat):
        report, seconds, size = end_to_end(doc)
        best = min(best, seconds)
    return report, best, size


def compile_chunk(doc: dict) -> float:
    """Compile the document's step chunk as `flexmech build` does: the compiler's seconds."""
    from flexmech.models import compile_mechanism, load_document
    from flexmech.service.kernels.build import BuildLimits, Compiler
    from flexmech.service.kernels.needs import builds_of

    seconds = 0.0
    for build in builds_of(compile_mechanism(load_document(copy.deepcopy(doc)))):
        for _, fn, target in build.functions:
            outcome = Compiler().build(fn, target, BuildLimits(120, 2**30))
            if not outcome.ok:
                raise RuntimeError(f"the chunk did not compile: {outcome.message}")
            seconds += outcome.seconds
    return seconds


def cold_and_warm(doc: dict) -> dict:
    cold = run(doc, 1)[1]
    compiled = compile_chunk(doc)
    report, warm, size = run(doc)
    return {"report": report, "cold": cold, "compile": compiled, "warm": warm, "bytes": size}


def energy_at(doc: dict, q: list[float], v: list[float], t: float) -> float:
    """T + elastic + gravity (J) of a state in SI, by flexmech's energy function."""
    parsed = MechanismDocument.model_validate(doc)
    spec = SimulateSpec.model_validate(doc["simulate"])
    model = model_of(parsed, spec)
    values = np.array(model.book.values)
    energy = ca.Function(
        "energy", [model.q, model.v, model.t, model.p], [model.kinetic + model.elastic + model.gravity]
    )
    return float(energy(q, v, t, model.book.parameter_vector(values)))


def si_state(report: dict, row: int) -> tuple[list[float], list[float]]:
    """(q, v) in SI of a report's kept state (its lengths in m, angles in deg)."""
    assert report["units"]["length"] == "m" and report["units"]["angle"] == "deg"
    scale = [1.0, 1.0, math.pi / 180]
    return (
        [report["coordinates"][f"hinge.{c}"][row] * f for c, f in zip("xy", scale)]
        + [report["coordinates"]["hinge.theta"][row] * scale[2]],
        [report["velocities"][f"hinge.{c}"][row] * f for c, f in zip("xy", scale)]
        + [report["velocities"]["hinge.theta"][row] * scale[2]],
    )


def peer_model(doc: dict, mu: float) -> dict:
    """The numbers the peer needs, from the document (SI: its units are m, N, kg, GPa, deg)."""
    flexure = doc["elements"].get("flexure")
    K, arm, frame = None, [0.0, 0.0], 0.0
    if flexure is not None:
        section = doc["sections"][flexure["section"]]
        EI = doc["materials"][flexure["material"]]["E"] * 1e9 * section["b"] * section["h"] ** 3 / 12
        K = np.array(stiffness(flexure["radius"], math.radians(flexure["arc_angle"]), EI)).tolist()
        end = math.radians(flexure["start_angle"] + flexure["arc_angle"])
        arm = [
            flexure["center"][0] + flexure["radius"] * math.cos(end),
            flexure["center"][1] + flexure["radius"] * math.sin(end),
        ]  # C1 - G1, G1 at the origin
        frame = end + math.pi / 2
    body, contacts = doc["bodies"]["hinge"], doc["contacts"]
    start = doc["simulate"]["initial"]["hinge"]
    return {
        "mass": body["mass"],
        "inertia": body["inertia"],
        "gravity": doc["gravity"],
        "flexure_K": K,
        "flexure_frame_angle": frame,
        "flexure_arm": arm,
        "pin_radius": contacts["sites"]["pin"]["radius"],
        "hole_radius": contacts["objects"]["hole"]["radius"],
        "restitution": contacts["pairs"]["conjugate"]["normal"]["restitution"],
        "mu": mu,
        "step": doc["simulate"]["step"],
        "until": doc["simulate"]["until"],
        "q0": start["displacement"][:2] + [math.radians(start["displacement"][2])],
        "v0": [0.0, 0.0, 0.0],
        "at": [0.1, 0.5, doc["simulate"]["until"]],
    }


def peer(model: dict) -> dict | None:
    if (
        not Path(PEER[0]).exists()
        or subprocess.run([PEER[0], "-c", "import siconos.kernel"], capture_output=True, check=False).returncode
    ):
        return None
    done = subprocess.run(PEER, input=json.dumps(model), capture_output=True, text=True, check=False, timeout=3600)
    if done.returncode:
        raise RuntimeError(f"the Siconos peer failed: {done.stderr[-2000:]}")
    return json.loads(done.stdout)


def state_at(report: dict, t: float) -> list[float]:
    times = np.asarray(report["times"])
    k = int(np.argmin(np.abs(times - t)))
    return [report["coordinates"][f"hinge.{c}"][k] for c in ("x", "y", "theta")]


def scipy_peer(doc: dict) -> dict:
    """The event-driven document run by scipy's solve_ivp on flexmech's right-hand side."""
    from benchmarks.scipy_events_peer import ScipyEvents
    from flexmech.service.impacts.run import MAX_STEP_PARTS, start_state
    from flexmech.service.impacts.stepping import event_settings

    began = time.perf_counter()
    parsed = MechanismDocument.model_validate(doc)
    spec = SimulateSpec.model_validate(doc["simulate"])
    model = model_of(parsed, spec)
    p = model.book.parameter_vector(np.array(model.book.values))
    q0, v0 = start_state(model, spec, p)
    longest = spec.max_step if spec.max_step is not None else spec.until / MAX_STEP_PARTS
    settings = event_settings(model, spec.until, spec.tolerance, longest)
    out = ScipyEvents(model, p).run(q0, v0, spec.until, spec.tolerance, settings[3:], longest)
    out["total"] = time.perf_counter() - began
    return out


def print_side(label: str, figures: dict) -> None:
    report = figures["report"]
    print(
        f"  {label}: cold {figures['cold'] / UNTIL:.3f} s/s (interpreted) + compile {figures['compile']:.2f} s; "
        f"warm {figures['warm'] / UNTIL:.4f} s/s end to end (stepping {report['seconds'] / UNTIL:.4f}); "
        f"{report['steps']} steps, {len(report['times'])} states kept, JSON {figures['bytes'] / 1e6:.2f} MB, "
        f"balance error {report['energy_balance_error']:.1e}"
    )


def main() -> None:
    if shutil.which("gcc") is None:
        print("note: no C compiler: flexmech runs on CasADi's virtual machine")
    event_doc = document("csfh.json", until=UNTIL)
    same_mu = coulomb(document("csfh.json", until=UNTIL, scheme="moreau", step=1e-5), 0.055, 0.055)
    kept = os.environ.get("FLEXMECH_CACHE_DIR")
    with tempfile.TemporaryDirectory() as cache:
        os.environ["FLEXMECH_CACHE_DIR"] = cache  # cold: nothing compiled yet
        try:
            moreau = cold_and_warm(same_mu)
            event = cold_and_warm(event_doc)
        finally:
            os.environ.pop("FLEXMECH_CACHE_DIR")
            if kept is not None:
                os.environ["FLEXMECH_CACHE_DIR"] = kept
    print(f"scenario 6.3, {UNTIL:g} s simulated; seconds per simulated second, end to end (model, steps, report, JSON)")
    print_side("flexmech Moreau-Jean h = 1e-5, Coulomb mu = 0.055", moreau)
    mine = moreau["report"]
    other = peer(peer_model(same_mu, 0.055))
    if other is None:
        print("  Siconos: not installed (apt-get install python3-siconos)")
    else:
        print(
            f"  Siconos 4.4 Moreau-Jean h = 1e-5, mu = 0.055: whole run {other['total'] / UNTIL:.3f} s/s, stepping "
            f"{other['seconds'] / UNTIL:.3f} s/s ({other['steps']} steps, {other['seconds'] / other['steps'] * 1e6:.1f} "
            "us per step)"
        )
        print(
            f"  Siconos' whole run / flexmech's warm whole run: {other['total'] / moreau['warm']:.0f}x; / flexmech's "
            f"cold run: {other['total'] / moreau['cold']:.1f}x"
        )
        ours = [round(hit["time"], 5) for hit in mine["impacts"][:3]]
        theirs = [round(hit["time"], 5) for hit in other["impacts"][:3]]
        print(f"  first impacts (s), flexmech {ours}, Siconos {theirs}")
        for t in (0.5,):
            print(
                f"  q at {t:g} s: flexmech {np.round(state_at(mine, t), 6).tolist()} (m, m, deg), Siconos "
                f"{np.round(np.array(other['states'][repr(t)]) * [1, 1, 180 / math.pi], 6).tolist()}"
            )
        print(
            f"  energy at 1 s (J): flexmech {energy_at(same_mu, *si_state(mine, -1), UNTIL):.6f}, Siconos "
            f"{energy_at(same_mu, other['final'], other['final_velocity'], UNTIL):.6f}"
        )
    print_side("flexmech event-driven LN + Ambrosio, tol 1e-10", event)
    scipy = scipy_peer(event_doc)
    mine = event["report"]
    print(
        f"  scipy solve_ivp RK45 + events, the same model and tolerances: {scipy['total'] / UNTIL:.3f} s/s "
        f"({scipy['steps']} steps)"
    )
    print(f"  scipy's / flexmech's warm whole run: {scipy['total'] / event['warm']:.0f}x")
    ours = [round(hit["time"], 6) for hit in mine["impacts"][:4]]
    print(f"  first contact onsets (s), flexmech {ours}, scipy {[round(t, 6) for t, _ in scipy['onsets'][:4]]}")
    n = 3  # the hinge's x, y, theta; scipy's states are [q, v, works]
    for t in (0.5, UNTIL):  # linear between each side's own steps
        theirs = [np.interp(t, scipy["times"], scipy["states"][:, k]) * f for k, f in enumerate([1, 1, 180 / math.pi])]
        ours = [np.interp(t, mine["times"], mine["coordinates"][f"hinge.{c}"]) for c in ("x", "y", "theta")]
        print(
            f"  q at {t:g} s: flexmech {np.round(ours, 7).tolist()}, scipy {np.round(theirs, 7).tolist()} (m, m, deg)"
        )
    final = scipy["states"][-1]
    print(
        f"  energy at 1 s (J): flexmech {energy_at(event_doc, *si_state(mine, -1), UNTIL):.6f}, scipy "
        f"{energy_at(event_doc, final[:n].tolist(), final[n : 2 * n].tolist(), UNTIL):.6f}"
    )
    paper = coulomb(document("csfh.json", until=0.5, scheme="moreau", step=1e-5), 0.11, 0.055)
    reference = run(paper, 1)[0]
    print("scenario 6.3, Moreau h = 1e-5, f_a = 0.11, f_d = 0.055:")
    print(
        "  first impacts at "
        + ", ".join(f"{hit['time']:.5f} s ({hit['impact_speed']:.4f} m/s)" for hit in reference["impacts"][:3])
    )
    print(f"  q at 0.5 s: {np.round(state_at(reference, 0.5), 7).tolist()} (m, m, deg)")
    central = run(document("csfh_central_impact.json", until=1.0, scheme="moreau", step=1e-5), 1)[0]
    first = central["impacts"][0]
    print(
        f"scenario 6.1, Moreau h = 1e-5: first impact at {first['time']:.5f} s, impulse {first['impulse']:.6f} N s, "
        f"rebound ratio {first['rebound_ratio']:.9f}; y at 1 s: {state_at(central, 1.0)[1]:.7f} m"
    )
    external = hertz_stiffness("spheres", 210e9, 0.3, 210e9, 0.3, 0.18, 0.20, "external", None)
    conformal = hertz_stiffness("spheres", 100e9, 0.3, 100e9, 0.3, 0.18, 0.20, "conformal", None)
    cylinders = hertz_stiffness("cylinders", 210e9, 0.3, 210e9, 0.3, 0.18, 0.20, "external", 0.025)
    print(
        f"Table 2: K spheres {external / 1e9:.3f}e9 N/m^1.5 (E = 210 GPa, R1 R2 / (R1 + R2)); K cylinders "
        f"{cylinders / 1e9:.4f}e9 N/m (E = 210 GPa, L = b); pin in hole, Table 1's E = 100 GPa, R1 R2 / (R2 - R1): "
        f"{conformal / 1e9:.2f}e9 N/m^1.5"
    )


if __name__ == "__main__":
    main()
