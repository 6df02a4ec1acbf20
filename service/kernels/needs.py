"""Which compiled kernels a document runs on: the chain signatures of its discretized links
(link dynamics), and for a rigid-body impact simulation its chunk of steps. Each is a Build:
a name, what it compiles (Functions and their libraries), and whether it is there already."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import casadi as ca

from flexmech.models import Mechanism, MechanismError
from flexmech.models.kernels.chain_signature import ChainSignature
from flexmech.models.kernels.chunks import chunks
from flexmech.models.kernels.layout import layout_of, runs_in_chains
from flexmech.service.kernels.cache import abandoned, library
from flexmech.service.kernels.queue import BUILD_ORDER, function_library, note_of


@dataclass
class Build:
    name: str
    functions: list[tuple[str, ca.Function, Path]]  # (part, Function, library)
    note: Path  # where an abandoned build is noted
    link: list[str] = field(default_factory=list)  # libraries the Functions call (a window: its kernels)

    @property
    def built(self) -> bool:
        return all(target.exists() for _, _, target in self.functions)


def chain_build(signature: ChainSignature) -> Build:
    functions = chunks(signature).functions()
    return Build(
        signature.key, [(kind, functions[kind], library(signature, kind)) for kind in BUILD_ORDER], abandoned(signature)
    )


def builds_of(mech: Mechanism) -> list[Build]:
    """The kernels a document's analyses run on (none for documents without dynamics)."""
    out = []
    if any(runs_in_chains(t) for t in mech.structure.elements):
        out += [chain_build(g.signature) for g in layout_of(mech.structure).groups]
    simulate = mech.document.simulate
    if simulate is not None and simulate.scheme in ("event_driven", "moreau"):
        from flexmech.service.impacts.run import check_laws, impact_model, timed_fields
        from flexmech.service.impacts.stepping import chunk_function

        model = impact_model(
            mech.document, timed_fields(mech.document, simulate), json.dumps(simulate.histories, sort_keys=True)
        )
        try:
            check_laws(model, simulate)
        except MechanismError:
            return out  # a run refuses these laws by name: there is nothing to build for it
        kind = "event" if simulate.scheme == "event_driven" else "moreau"
        fn, key = chunk_function(model, kind)
        target = function_library(fn, key)
        out.append(Build(f"impact_{kind}_{target.stem}", [(kind, fn, target)], note_of(target)))
    return out


def window_builds(mech: Mechanism) -> list[Build]:
    """The window of time steps the document's link dynamics runs, compiled as a whole
    (service.kernels.windows): only once every kernel it calls is compiled, and none for a
    document without such a simulation."""
    from flexmech.service.dynamics.adaptive import ADAPTIVE_WINDOW
    from flexmech.service.dynamics.histories import read_histories
    from flexmech.service.dynamics.run import scheme_of, simulation_spec
    from flexmech.service.dynamics.stepping import WINDOW, engine_of, window_length
    from flexmech.service.kernels.windows import links, window_key

    if mech.document.simulate is None or mech.document.simulate.scheme in ("event_driven", "moreau"):
        return []
    if not any(runs_in_chains(t) for t in mech.structure.elements):
        return []
    try:
        spec = simulation_spec(mech)
        histories = read_histories(mech, spec.histories, spec.until, "/simulate/histories")
    except MechanismError:
        return []
    engine = engine_of(mech.structure, scheme_of(spec), histories)
    signatures = [g.signature for g in engine.system.layout.groups]
    if any(s not in engine.compiled for s in signatures):
        return []
    fn = engine.glue_window(window_length(engine.scheme, ADAPTIVE_WINDOW if spec.adaptive else WINDOW))
    target = function_library(fn, window_key(fn))
    return [Build(f"window_{target.stem}", [("window", fn, target)], note_of(target), link=links(signatures))]
