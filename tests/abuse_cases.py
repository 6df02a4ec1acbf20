"""Requests that once broke the service (issues 12 and 24), as data: each with the status, the JSON
pointer and a piece of the message it must get. tests/service/test_abuse.py sends them to a live
server; the hardening tests use single cases."""

from __future__ import annotations

import copy
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
ACTUATION = "/loads/actuation/force/1"


@dataclass(frozen=True)
class Case:
    name: str
    path: str  # /v1/solve, /v1/sweeps or /v1/simulations
    body: Any  # JSON-able, or bytes sent as they are
    status: int
    pointer: str | None
    message: str  # a piece of the message


def gripper() -> dict:
    return json.loads((EXAMPLES / "gripper.json").read_text())


def cantilever() -> dict:
    return json.loads((EXAMPLES / "cantilever.json").read_text())


def changed(document: dict, change) -> dict:
    document = copy.deepcopy(document)
    change(document)
    return document


def heavy_links() -> dict:
    """8 links of 64 intervals of order 12 (2.3 KB): 113 s and 1.4 GB to build, once."""
    doc = cantilever()
    beam = doc["elements"].pop("beam")
    for k in range(8):
        doc["bodies"][f"tip{k}"] = {"joint": True, "position": [101.6, 0]}
        doc["elements"][f"L{k}"] = dict(beam, to=f"tip{k}", intervals=64, order=12)
    doc["loads"]["F"]["body"] = "tip0"
    doc["outputs"]["tip"]["body"] = "tip0"
    return doc


def shape_expression(text: str) -> dict:
    return changed(
        cantilever(), lambda d: d["elements"]["beam"].update(shape={"type": "expression", "expression": text})
    )


def sweep(path: str, **parameter) -> dict:
    return {"example": "gripper", "parameters": [{"path": path, **parameter}]}


def grid(counts: list[int]) -> dict:
    paths = [
        "/loads/actuation/force/1",
        "/loads/actuation/force/0",
        "/sections/flexure/h",
        "/sections/flexure/b",
        "/elements/a/radius",
    ]
    return {
        "example": "gripper",
        "parameters": [{"path": p, "start": 0.1, "stop": 0.2, "steps": n - 1} for p, n in zip(paths, counts)],
    }


def cases() -> list[Case]:
    solve, sweeps = "/v1/solve", "/v1/sweeps"
    radius = "/document/elements/a/radius"
    return [
        Case(
            "a billion steps",
            sweeps,
            sweep(ACTUATION, start=0, stop=1, steps=10**9),
            422,
            "/parameters",
            "1000000001 sweep points: the limit is",
        ),
        Case(
            "a 30-digit step count",
            sweeps,
            sweep(ACTUATION, start=0, stop=1, steps=10**30),
            422,
            "/parameters",
            "sweep points: the limit is",
        ),
        Case("a grid past 2^64", sweeps, grid([65536] * 5), 422, "/parameters", "sweep points: the limit is"),
        Case(
            "a grid of exactly 2^64", sweeps, grid([65536] * 4), 422, "/parameters", "18446744073709551616 sweep points"
        ),
        Case(
            "8 links x 64 intervals x order 12",
            solve,
            {"document": heavy_links()},
            422,
            "/document/elements/L0/intervals",
            "units of graph work",
        ),
        Case(
            "a link of 128 elements",
            solve,
            {
                "document": changed(
                    json.loads((EXAMPLES / "rod_free_vibration.json").read_text()),
                    lambda d: d["elements"]["rod"].update(intervals=128),
                )
            },
            422,
            "/document/elements/rod/intervals",
            "128 elements: the service takes at most 64 in one link",
        ),
        Case(
            "10**10**10 mm",
            solve,
            {"document": changed(gripper(), lambda d: d["elements"]["a"].update(radius="10**10**10 mm"))},
            422,
            radius,
            "cannot read '10**10**10 mm' as a quantity",
        ),
        Case(
            "10**10**7 mm",
            solve,
            {"document": changed(gripper(), lambda d: d["elements"]["a"].update(radius="10**10**7 mm"))},
            422,
            radius,
            "as a quantity",
        ),
        Case(
            "a 30,000-digit number string",
            solve,
            {"document": changed(gripper(), lambda d: d["elements"]["a"].update(radius="1" * 30000 + " mm"))},
            422,
            radius,
            "a text of 30003 characters: no text of a document may be longer than 20000",
        ),
        Case(
            "a 990,000-character description",
            sweeps,
            {
                "document": dict(gripper(), description="d" * 990_000),
                "parameters": [{"path": ACTUATION, "values": [0.0]}],
            },
            422,
            "/document/description",
            "/document/description: at most 20000 characters (got 990000)",
        ),
        Case(
            "a 900,000-character name",
            solve,
            {"document": dict(gripper(), name="n" * 900_000)},
            422,
            "/document/name",
            "/document/name: at most 200 characters (got 900000)",
        ),
        Case(
            "a body named with 300,000 characters",
            solve,
            {"document": changed(gripper(), lambda d: d["bodies"].update({"b" * 300_000: d["bodies"]["input"]}))},
            422,
            "/document/bodies",
            "a key of 300000 characters: keys here are at most 256 characters",
        ),
        Case(
            "true as a radius",
            solve,
            {"document": changed(gripper(), lambda d: d["elements"]["a"].update(radius=True))},
            422,
            radius,
            "expected a number",
        ),
        Case(
            "5 percent as a force",
            solve,
            {"document": gripper(), "overrides": {ACTUATION: "5 percent"}},
            422,
            "/overrides/~1loads~1actuation~1force~11",
            "'5 percent' is not a force",
        ),
        Case(
            "5 rad as a modulus",
            solve,
            {"document": changed(gripper(), lambda d: d["materials"]["silicon"].update(E="5 rad"))},
            422,
            "/document/materials/silicon/E",
            "'5 rad' is not a stress",
        ),
        Case(
            "mm alone",
            solve,
            {"document": changed(gripper(), lambda d: d["elements"]["a"].update(radius="mm"))},
            422,
            radius,
            "expected a number",
        ),
        Case(
            "duplicate keys",
            solve,
            b'{"example": "gripper", "example": "gripper_nylon"}',
            422,
            None,
            "the body gives the key 'example' twice in one object",
        ),
        Case(
            "a radius swept to -1",
            sweeps,
            {"example": "gripper", "parameters": [{"path": "/elements/a/radius", "values": [0.2, -1]}]},
            422,
            "/parameters/0/values/1",
            "must be positive",
        ),
        Case(
            "an arc angle of 400 deg",
            sweeps,
            {"example": "gripper", "parameters": [{"path": "/elements/a/arc_angle", "values": [400]}]},
            422,
            "/parameters/0/values/0",
            "arc angle must lie in (0, 360) deg",
        ),
        *[
            Case(
                f"shape {text}",
                solve,
                {"document": shape_expression(text)},
                422,
                "/document/elements/beam/shape/expression",
                message,
            )
            for text, message in (
                ("1/0", "not a finite number"),
                ("0**-1", "not a finite number"),
                ("9**9**9", "not a finite number"),
                ("(-1)**0.5", "not a finite number"),
                ("10**400", "not a finite number"),
                ("sqrt(-1)", "not a finite number"),
                ("log(0)", "not a finite number"),
                ("exp(1000)*0", "not a finite number"),
                ("-" * 979 + "u", "nested too deeply"),
            )
        ],
        *[
            Case(f"{value:g} in {where}", solve, {"document": changed(gripper(), change)}, 422, pointer, "out of range")
            for value in (1e308, 1e-320, 5e-324)
            for where, change, pointer in (
                ("a radius", lambda d, v=value: d["elements"]["a"].update(radius=v), radius),
                ("E", lambda d, v=value: d["materials"]["silicon"].update(E=v), "/document/materials/silicon/E"),
                (
                    "a position",
                    lambda d, v=value: d["bodies"]["input"].update(position=[v, 0.2]),
                    "/document/bodies/input/position/0",
                ),
                (
                    "an angle",
                    lambda d, v=value: d["elements"]["a"].update(start_angle=v),
                    "/document/elements/a/start_angle",
                ),
            )
        ],
        Case(
            "uN/0 as a unit",
            solve,
            {"document": changed(gripper(), lambda d: d["units"].update(force="uN/0"))},
            422,
            "/document/units/force",
            "is not a unit of force",
        ),
        Case(
            "1,500 chained unit factors",
            solve,
            {"document": changed(gripper(), lambda d: d["units"].update(length="*".join(["mm"] * 1500)))},
            422,
            "/document/units/length",
            "at most 64 characters",
        ),
        Case(
            "NaN displacements",
            solve,
            b'{"example": "gripper", "analysis": "inverse", "displacements": {"input": [NaN, 0, 0]}}',
            422,
            "/displacements/input/0",
            "finite",
        ),
        Case(
            "a 4,300-digit integer",
            solve,
            b'{"example": "gripper", "overrides": {"/loads/actuation/force/1": ' + b"1" * 4400 + b"}}",
            400,
            None,
            "not valid JSON",
        ),
        # issue 24: runs costed before they start
        Case(
            "the CSFH until 1e9 s",
            solve,
            {"example": "csfh", "analysis": "simulate", "simulate": {"until": 1e9}},
            422,
            "/simulate/step",
            "1e+09 s in steps of 0.0001 s would be more than 1e+12 steps",
        ),
        Case(
            "the CSFH until 1e9 s as a job",
            "/v1/simulations",
            {"example": "csfh", "simulate": {"until": 1e9}},
            422,
            "/simulate/step",
            "1e+09 s in steps of 0.0001 s would be more than 1e+12 steps",
        ),
        Case(
            "the asymmetric CSFH until 1e6 s",
            solve,
            {"example": "csfh_asymmetric_impact", "analysis": "simulate", "simulate": {"until": 1e6}},
            422,
            "/simulate/until",
            "1e+06 s from a first step of 0.0001 s is costed at 1e+10 steps, over the limit",
        ),
        Case(
            "20 s of Moreau steps of 1e-5 s",
            solve,
            {"example": "csfh", "analysis": "simulate", "simulate": {"scheme": "moreau", "step": 1e-5, "until": 20.0}},
            422,
            "/simulate/until",
            "of states, over the 192 MiB one run may take",
        ),
        Case(
            "deep JSON",
            solve,
            b'{"example": "gripper", "options": ' + b"[" * 5000 + b"]" * 5000 + b"}",
            400,
            None,
            "nests deeper than",
        ),
    ]
