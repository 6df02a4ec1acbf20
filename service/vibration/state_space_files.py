"""A state-space model (service.vibration.state_space) as a file and as a python-control system.

By the file's suffix: .json (the report's `state_space`: nested lists, names and units), .npz
(numpy) and .mat (MATLAB, scipy.io.savemat): the matrices A, B, C, D, M, K, Dmp (the damping
matrix: D is the feedthrough), G and Phi (the shapes, x = Phi eta), the names as cell arrays
(states, inputs, outputs, coordinates) with their units (state_units, ...), the modes' kinds, the poles (complex,
rad/s) and the static gain (left out with a rigid mode), and `units_json`, every unit as JSON.
python-control is imported only where its StateSpace is made (the CLI stays quick)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from flexmech.service.vibration.state_space import MATRICES, NAMES, StateSpaceModel

SUFFIXES = (".json", ".npz", ".mat")
LISTS = (*NAMES, "kinds")  # per mode: elastic, rigid or unstable
FILE_NAMES = {"damping": "Dmp", "shapes": "Phi"}  # in .npz and .mat: MATLAB's D is the feedthrough


def write_state_space(model: StateSpaceModel, path: Path) -> None:
    """Write `model` in the format its suffix names (SUFFIXES; ValueError for another)."""
    suffix = Path(path).suffix.lower()
    if suffix not in SUFFIXES:
        raise ValueError(f"cannot tell the format of '{path}': use a name ending in {', '.join(SUFFIXES)}")
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    if suffix == ".json":
        from flexmech.service.solvers.reports import plain

        Path(path).write_text(json.dumps(plain(model.to_dict())))
        return
    variables = _variables(model)
    if suffix == ".npz":
        arrays: dict[str, Any] = {name: np.asarray(value) for name, value in variables.items()}
        np.savez(path, **arrays)
        return
    from scipy.io import savemat

    cells = {name: np.array(value, dtype=object) for name, value in variables.items() if isinstance(value, list)}
    savemat(path, {**variables, **cells}, do_compression=True)


def read_state_space(path: Path) -> StateSpaceModel:
    """The model of a file write_state_space wrote."""
    suffix = Path(path).suffix.lower()
    if suffix == ".json":
        return StateSpaceModel.from_dict(json.loads(Path(path).read_text()))
    if suffix == ".npz":
        with np.load(path, allow_pickle=False) as stored:
            found = {name: stored[name] for name in stored.files}
        names = {name: [str(v) for v in found[name]] for name in LISTS}
    else:
        from scipy.io import loadmat

        found = loadmat(path)
        names = {name: [str(np.ravel(cell)[0]) for cell in np.ravel(found[name])] for name in LISTS}
    matrices = {name: found[FILE_NAMES.get(name, name)] for name in MATRICES}
    units = json.loads(str(np.ravel(found["units_json"])[0]))
    return StateSpaceModel.from_dict({**matrices, **names, "units": units})


def _variables(model: StateSpaceModel) -> dict[str, Any]:
    """The file's variables: the matrices, the names and their units (lists), poles, static gain."""
    found: dict[str, Any] = {FILE_NAMES.get(name, name): getattr(model, name) for name in MATRICES}
    for name in NAMES:
        found[name] = list(getattr(model, name))
        found[f"{name[:-1]}_units"] = list(model.units[name])
    found["poles"] = model.poles
    gain = model.static_gain
    if gain is not None:
        found["static_gain"] = gain
    found["kinds"] = list(model.kinds)
    found["units_json"] = json.dumps(model.units)
    return found


def control_system(model: StateSpaceModel) -> Any:
    """The model as python-control's StateSpace (continuous time, s), its signals named as the
    model's with '.' made '_' (python-control keeps '.' for system.signal: tip.y is tip_y)."""
    import control

    inputs, outputs, states = ([signal_name(n) for n in names] for names in (model.inputs, model.outputs, model.states))
    return control.ss(model.A, model.B, model.C, model.D, inputs=inputs, outputs=outputs, states=states)


def signal_name(name: str) -> str:
    """A flexmech name as a python-control signal's (no '.')."""
    return name.replace(".", "_")
