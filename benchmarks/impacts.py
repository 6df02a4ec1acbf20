"""Speed of seed 004's impact models against a peer, side by side in one run, on 1 s of
scenario 6.3 (the CSFH from q0 = [0.01, 0.01, 0]; examples/csfh.json):

  flexmech event-driven: Lankarani-Nikravesh (K cylinders of Table 2) with Ambrosio friction,
      Dormand-Prince steps at a local error of 1e-10, contact and slip events located;
  flexmech Moreau-Jean at h = 1e-5, with Coulomb friction;
  Siconos (Debian's python3-siconos, run by /usr/bin/python3: benchmarks/siconos_peer.py),
      Moreau-Jean at h = 1e-5 on the same model: the same flexure (constant stiffness), gravity,
      pin in hole, e_N = 0.9, its one Coulomb coefficient mu.

Siconos has a single friction coefficient, so the side-by-side Moreau runs take f_a = f_d =
0.055 on both sides (and their trajectories are compared); the paper's f_a = 0.11, f_d =
0.055 run gives the reference figures below. Times are the stepping alone on both sides (the
model building, the compile, which happens once per structure and is cached, and the
report are apart); flexmech's are the best of three runs.

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
import shutil
import subprocess
from pathlib import Path

import numpy as np

from models.curved_beam import stiffness
from models.document import MechanismDocument
from models.impacts.laws import hertz_stiffness
from models.simulation_spec import SimulateSpec
from service.impacts.run import run_impacts

ROOT = Path(__file__).resolve().parents[1]
PEER = ["/usr/bin/python3", str(ROOT / "benchmarks" / "siconos_peer.py")]
UNTIL = 1.0


def document(name: str, **simulate) -> dict:
    doc = json.loads((ROOT / "examples" / name).read_text())
    doc["simulate"].update(simulate)
    return doc


def coulomb(doc: dict, adherence: float, sliding: float) -> dict:
    doc = copy.deepcopy(doc)
    doc["impacts"]["pairs"]["conjugate"]["friction"] = {"law": "coulomb", "adherence": adherence, "sliding": sliding}
    return doc


def run(doc: dict, repeat: int = 3) -> tuple[dict, float]:
    """(report, best seconds of stepping)."""
    parsed = MechanismDocument.model_validate(doc)
    spec = SimulateSpec.model_validate(doc["simulate"])
    best, report = math.inf, None
    for _ in range(repeat):
        _, report = run_impacts(parsed, spec)
        best = min(best, report["seconds"])
    return report, best


def peer_model(doc: dict, mu: float) -> dict:
    """The numbers the peer needs, from the document (SI: its units are m, N, kg, GPa, deg)."""
    flexure = doc["elements"].get("flexure")
    K, arm, frame = None, [0.0, 0.0], 0.0
    if flexure is not None:
        section = doc["sections"][flexure["section"]]
        EI = doc["materials"][flexure["material"]]["E"] * 1e9 * section["b"] * section["h"] ** 3 / 12
        K = np.array(stiffness(flexure["radius"], math.radians(flexure["arc_angle"]), EI)).tolist()
        end = math.radians(flexure["start_angle"] + flexure["arc_angle"])
        arm = [flexure["center"][0] + flexure["radius"] * math.cos(end),
               flexure["center"][1] + flexure["radius"] * math.sin(end)]  # C1 - G1, G1 at the origin
        frame = end + math.pi / 2
    body, surfaces = doc["bodies"]["hinge"], doc["impacts"]["surfaces"]
    start = doc["simulate"]["initial"]["hinge"]
    return {"mass": body["mass"], "inertia": body["inertia"], "gravity": doc["gravity"], "flexure_K": K,
            "flexure_frame_angle": frame, "flexure_arm": arm, "pin_radius": surfaces["pin"]["radius"],
            "hole_radius": surfaces["hole"]["radius"],
            "restitution": doc["impacts"]["pairs"]["conjugate"]["normal"]["restitution"], "mu": mu,
            "step": doc["simulate"]["step"], "until": doc["simulate"]["until"],
            "q0": start["displacement"][:2] + [math.radians(start["displacement"][2])], "v0": [0.0, 0.0, 0.0],
            "at": [0.1, 0.5, doc["simulate"]["until"]]}


def peer(model: dict) -> dict | None:
    if not Path(PEER[0]).exists() or subprocess.run([PEER[0], "-c", "import siconos.kernel"],
                                                    capture_output=True, check=False).returncode:
        return None
    done = subprocess.run(PEER, input=json.dumps(model), capture_output=True, text=True, check=False, timeout=3600)
    if done.returncode:
        raise RuntimeError(f"the Siconos peer failed: {done.stderr[-2000:]}")
    return json.loads(done.stdout)


def state_at(report: dict, t: float) -> list[float]:
    times = np.asarray(report["times"])
    k = int(np.argmin(np.abs(times - t)))
    return [report["coordinates"][f"hinge.{c}"][k] for c in ("x", "y", "theta")]


def main() -> None:
    if shutil.which("gcc") is None:
        print("note: no C compiler: flexmech runs on CasADi's virtual machine")
    event_doc = document("csfh.json", until=UNTIL)
    moreau_doc = document("csfh.json", until=UNTIL, scheme="moreau", step=1e-5)
    run(event_doc, 1)  # builds and compiles (cached), timed apart
    event, event_s = run(event_doc)
    same_mu = coulomb(moreau_doc, 0.055, 0.055)
    run(same_mu, 1)
    moreau, moreau_s = run(same_mu)
    print(f"scenario 6.3, {UNTIL:g} s simulated (seconds of stepping per simulated second)")
    print(f"  flexmech event-driven LN + Ambrosio, tol 1e-10: {event_s / UNTIL:.4f} s/s "
          f"({event['steps']} steps, {event['trial_steps']} trial steps, {len(event['impacts'])} contacts, "
          f"balance error {event['energy_balance_error']:.1e})")
    print(f"  flexmech Moreau-Jean h = 1e-5, mu = 0.055:       {moreau_s / UNTIL:.4f} s/s "
          f"({moreau['steps']} steps, {moreau_s / moreau['steps'] * 1e6:.2f} us per step)")
    other = peer(peer_model(same_mu, 0.055))
    if other is None:
        print("  Siconos: not installed (apt-get install python3-siconos)")
    else:
        print(f"  Siconos Moreau-Jean h = 1e-5, mu = 0.055:        {other['seconds'] / UNTIL:.4f} s/s "
              f"({other['seconds'] / other['steps'] * 1e6:.2f} us per step)")
        print(f"  Siconos / flexmech Moreau: {other['seconds'] / moreau_s:.0f}x; "
              f"Siconos / flexmech event-driven: {other['seconds'] / event_s:.0f}x")
        ours = [round(hit["time"], 5) for hit in moreau["impacts"][:3]]
        theirs = [round(hit["time"], 5) for hit in other["impacts"][:3]]
        print(f"  first impacts (s), flexmech {ours}, Siconos {theirs}")
        for t in (0.1, 0.5):
            print(f"  q at {t:g} s: flexmech {np.round(state_at(moreau, t), 6).tolist()} (m, m, deg), Siconos "
                  f"{np.round(np.array(other['states'][repr(t)]) * [1, 1, 180 / math.pi], 6).tolist()}")
    paper = coulomb(document("csfh.json", until=0.5, scheme="moreau", step=1e-5), 0.11, 0.055)
    reference, _ = run(paper, 1)
    print("scenario 6.3, Moreau h = 1e-5, f_a = 0.11, f_d = 0.055:")
    print("  first impacts at " + ", ".join(f"{hit['time']:.5f} s ({hit['impact_speed']:.4f} m/s)"
                                              for hit in reference["impacts"][:3]))
    print(f"  q at 0.5 s: {np.round(state_at(reference, 0.5), 7).tolist()} (m, m, deg)")
    central, _ = run(document("csfh_central_impact.json", until=1.0, scheme="moreau", step=1e-5), 1)
    first = central["impacts"][0]
    print(f"scenario 6.1, Moreau h = 1e-5: first impact at {first['time']:.5f} s, impulse {first['impulse']:.6f} N s, "
          f"rebound ratio {first['rebound_ratio']:.9f}; y at 1 s: {state_at(central, 1.0)[1]:.7f} m")
    external = hertz_stiffness("spheres", 210e9, 0.3, 210e9, 0.3, 0.18, 0.20, "external", None)
    conformal = hertz_stiffness("spheres", 100e9, 0.3, 100e9, 0.3, 0.18, 0.20, "conformal", None)
    cylinders = hertz_stiffness("cylinders", 210e9, 0.3, 210e9, 0.3, 0.18, 0.20, "external", 0.025)
    print(f"Table 2: K spheres {external / 1e9:.3f}e9 N/m^1.5 (E = 210 GPa, R1 R2 / (R1 + R2)); K cylinders "
          f"{cylinders / 1e9:.4f}e9 N/m (E = 210 GPa, L = b); pin in hole, Table 1's E = 100 GPa, R1 R2 / (R2 - R1): "
          f"{conformal / 1e9:.2f}e9 N/m^1.5")


if __name__ == "__main__":
    main()
