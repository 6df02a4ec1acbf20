"""A mechanism that differs from one seen before only in its names shares its graphs
(models.documents.naming): no graph is built again, its results and labels are its own, and a server
sent documents with ever new names keeps its memory and its disk cache flat."""

from __future__ import annotations

import copy
import json

import httpx
import numpy as np
import pytest
from conftest import EXAMPLES
from servers import ApiServer

from flexmech.models import compile_mechanism, load_document
from flexmech.models.documents.naming import anonymous
from flexmech.models.graph.assembly import graphs_for
from flexmech.service.solvers.equilibrium import solve_equilibrium
from flexmech.service.solvers.sweep import solve_for_target

ACTUATION = "/loads/actuation/force/1"
NAMED = ("materials", "sections", "bodies", "elements", "loads", "outputs")


def renamed(doc: dict, rename) -> dict:
    """The document with every name n replaced by rename(n), references and pointers too."""
    doc = copy.deepcopy(doc)
    for section in NAMED:
        doc[section] = {rename(k): v for k, v in doc.get(section, {}).items()}
    for element in doc["elements"].values():
        for field in ("from", "to", "material", "section"):
            element[field] = rename(element[field])
    for item in (*doc["loads"].values(), *doc["outputs"].values()):
        item["body"] = rename(item["body"])
    doc.pop("sweep", None)
    return doc


def test_a_renamed_gripper_shares_the_graphs_and_reaches_the_same_closing_force(gripper_dict):
    original = compile_mechanism(load_document(renamed(gripper_dict, lambda n: n)))
    # names that are also words of the structure's vocabulary (models, locations, kinds)
    vocabulary = iter(
        [
            "exact",
            "linear",
            "reference",
            "at",
            "force",
            "moment",
            "x",
            "pinned",
            "clamped",
            "end",
            "start",
            "offset",
            "point",
        ]
    )
    words: dict[str, str] = {}

    def word(name: str) -> str:
        if name not in words:
            words[name] = next(vocabulary)
        return words[name]

    other = compile_mechanism(load_document(renamed(gripper_dict, word)))
    assert other.graphs.residual is original.graphs.residual  # the same Function: nothing built
    assert other.structure.key != original.structure.key and other.structure.unnamed == original.structure.unnamed

    mine = solve_for_target(original, ACTUATION, "end_effector.x", 0.0)
    theirs = solve_for_target(other, f"/loads/{words['actuation']}/force/1", f"{words['end_effector']}.x", 0.0)
    assert mine.value == pytest.approx(77.0346, abs=1e-4)
    assert theirs.value == pytest.approx(mine.value, rel=1e-12)

    names = other.graphs.output_names
    assert f"bodies.{words['coupler']}.x" in names and f"{words['end_effector']}.x" in names
    assert [n for n in names if "⟨" in n] == []
    assert len(names) == len(original.graphs.output_names)
    drawn = {segment[0] for segment in other.graphs.shape_segments}
    assert drawn == {words[n] for n in ("a", "b", "c", "d")}
    a = solve_equilibrium(original)
    b = solve_equilibrium(other)
    np.testing.assert_allclose(b.z, a.z, rtol=0, atol=1e-14)


def test_an_output_named_like_its_body_and_renamed_is_the_same_structure():
    """Names are tokens within their collection: the six-bar's outputs "J2" and "J4" (named
    like their bodies) renamed alone leave the structure as it was; a body renamed alone, too."""
    doc = json.loads((EXAMPLES / "six_bar.json").read_text())
    base = compile_mechanism(load_document(doc)).structure
    outputs = copy.deepcopy(doc)
    outputs["outputs"] = {f"point_{name}": spec for name, spec in doc["outputs"].items()}
    bodies = renamed(doc, lambda n: "hub" if n == "J3" else n)
    for variant in (outputs, bodies):
        structure = compile_mechanism(load_document(variant)).structure
        assert structure != base and structure.unnamed == base.unnamed


def test_a_structure_with_the_models_permuted_is_not_taken_for_a_renaming(gripper_dict):
    """The renaming touches names only: two grippers whose flexures swap models (and names)
    are different structures with different graphs."""
    first = copy.deepcopy(gripper_dict)
    first["elements"]["a"]["model"], first["elements"]["b"]["model"] = "linear", "partial_nonlinear"
    second = copy.deepcopy(first)
    second["elements"]["a"]["model"], second["elements"]["b"]["model"] = "partial_nonlinear", "linear"
    one, two = (compile_mechanism(load_document(d)).structure for d in (first, second))
    assert one.unnamed != two.unnamed
    assert graphs_for(one).residual is not graphs_for(two).residual


def test_names_that_look_like_tokens_keep_their_own_graphs(gripper_dict):
    doc = renamed(gripper_dict, lambda n: "⟨1⟩" if n == "coupler" else n)
    mech = compile_mechanism(load_document(doc))
    unnamed, names = anonymous(mech.structure)
    assert unnamed is mech.structure and names == ()
    assert "bodies.⟨1⟩.x" in mech.graphs.output_names
    assert solve_for_target(mech, ACTUATION, "end_effector.x", 0.0).value == pytest.approx(77.0346, abs=1e-4)


def _rss_mb(pid: int) -> float:
    for line in open(f"/proc/{pid}/status"):
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    raise AssertionError("no VmRSS")


def test_a_server_sent_ever_new_names_keeps_its_memory_and_cache_flat(gripper_dict, tmp_path):
    cache = tmp_path / "cache"
    server = ApiServer(
        {
            "FLEXMECH_DATA_DIR": str(tmp_path / "data"),
            "FLEXMECH_CACHE_DIR": str(cache),
            "FLEXMECH_API_KEYS": "",
            "FLEXMECH_WORKERS": "1",
            "FLEXMECH_BUILD_KERNELS": "0",
        },
        tmp_path / "server.log",
    )
    try:
        with httpx.Client(base_url=server.url, timeout=60) as client:

            def solve(k: int) -> float:
                doc = renamed(gripper_dict, lambda n: f"{n}_{k}")
                answer = client.post(
                    "/v1/solve",
                    json={
                        "document": doc,
                        "target": {
                            "path": f"/loads/actuation_{k}/force/1",
                            "output": f"end_effector_{k}.x",
                            "equals": 0,
                        },
                    },
                )
                assert answer.status_code == 200, answer.text
                return answer.json()["target"]["value"]

            for k in range(20):  # warm: the first structure built, allocators settled
                solve(k)
            before = _rss_mb(server.proc.pid)
            forces = [solve(k) for k in range(20, 220)]
            after = _rss_mb(server.proc.pid)
    finally:
        server.stop()
    assert max(forces) - min(forces) < 1e-9 * abs(forces[0]) and forces[0] == pytest.approx(77.0346, abs=1e-4)
    # each new structure used to add 35-40 MB: 200 of them, gigabytes
    assert after - before < 40, f"server memory grew from {before:.0f} to {after:.0f} MB over 200 renamed requests"
    assert len(list((cache / "graphs").iterdir())) == 1
