"""Drawings for fabrication (issue 51, acceptance 4): the gripper's DXF and GDS read back with
ezdxf and gdstk: one closed outline per body and flexure on its layer, each curved flexure's arcs
of radius r +- h/2 over the document's arc angle, the bounding box the document's geometry makes;
a link's outline its width apart; the command run twice; over HTTP, with a hostile name kept out
of the files and the file name."""

from __future__ import annotations

import io
import json
import math

import ezdxf
import gdstk
import httpx
import numpy as np
import pytest
from conftest import EXAMPLES
from typer.testing import CliRunner

import flexmech
from flexmech.api.cli import app
from flexmech.service.drawings.drawing import mechanism_drawing
from flexmech.service.drawings.fabrication import CHORD_ERROR, MARGIN_SPAN, MARGIN_WIDTHS, fabrication
from flexmech.service.drawings.fabrication_files import GDS_LAYERS, dxf_bytes, gds_bytes

GRIPPER = json.loads((EXAMPLES / "gripper.json").read_text())
H = 0.005  # mm
ENV = {"COLUMNS": "200", "FORCE_COLOR": None, "TTY_COMPATIBLE": None, "NO_COLOR": "1"}


def read_dxf(data: bytes):
    return ezdxf.read(io.StringIO(data.decode("utf-8")))


def read_gds(data: bytes, tmp_path) -> gdstk.Cell:
    path = tmp_path / "drawing.gds"
    path.write_bytes(data)
    library = gdstk.read_gds(str(path))
    assert len(library.cells) == 1
    return library.cells[0]


def expected_box() -> np.ndarray:
    """[[xmin, ymin], [xmax, ymax]] from the document: each flexure's annular sector (its arcs'
    ends and the axis directions inside its span) and each body's attachment points grown by its
    margin (a convex hull grown by a disc reaches exactly its points' box plus the margin)."""
    points = []
    for element in GRIPPER["elements"].values():
        (cx, cy), r, start, sweep = element["center"], element["radius"], element["start_angle"], element["arc_angle"]
        angles = [start, start + sweep] + [a for a in range(-360, 721, 90) if start < a < start + sweep]
        points += [
            (cx + rr * math.cos(math.radians(a)), cy + rr * math.sin(math.radians(a)))
            for a in angles
            for rr in (r - H / 2, r + H / 2)
        ]
    drawing = mechanism_drawing(flexmech.load(GRIPPER))
    span = max(
        np.ptp(
            [p for e in drawing["elements"] for p in e["points"]]
            + [b["reference"] for b in drawing["bodies"].values()],
            axis=0,
        )
    )
    for body in drawing["bodies"].values():
        margin = max(MARGIN_WIDTHS * H, MARGIN_SPAN * span)
        hull = np.array([body["reference"], *body["skeleton"]])
        points += [tuple(hull.min(axis=0) - margin), tuple(hull.max(axis=0) + margin)]
    points = np.array(points)
    return np.array([points.min(axis=0), points.max(axis=0)])


def test_the_dxf_has_one_closed_outline_per_body_and_flexure_with_true_arcs():
    doc = read_dxf(dxf_bytes(fabrication(flexmech.load(GRIPPER))))
    space = doc.modelspace()
    assert {layer.dxf.name for layer in doc.layers} >= {"bodies", "flexures", "anchors"}
    layers = [e.dxf.layer for e in space]
    assert sorted(layers) == ["anchors"] + ["bodies"] * 3 + ["flexures"] * 4
    assert all(e.dxftype() == "LWPOLYLINE" and e.closed for e in space)
    assert doc.header["$INSUNITS"] == 4  # millimetres
    for outline, element in zip(space.query('LWPOLYLINE[layer=="flexures"]'), GRIPPER["elements"].values()):
        arcs = [v for v in outline.virtual_entities() if v.dxftype() == "ARC"]
        assert sorted(a.dxf.radius for a in arcs) == pytest.approx(
            [element["radius"] - H / 2, element["radius"] + H / 2], abs=1e-9
        )
        for arc in arcs:
            assert (arc.dxf.end_angle - arc.dxf.start_angle) % 360 == pytest.approx(element["arc_angle"], abs=1e-9)
            assert (arc.dxf.start_angle - element["start_angle"] + 180) % 360 - 180 == pytest.approx(0.0, abs=1e-9)
            assert arc.dxf.center[0] == pytest.approx(element["center"][0], abs=1e-9)
            assert arc.dxf.center[1] == pytest.approx(element["center"][1], abs=1e-9)
    assert dxf_box(space) == pytest.approx(expected_box(), abs=1e-9)


def dxf_box(space) -> np.ndarray:
    """The drawing's extent as read back: every vertex, and every arc's points on the axis
    directions within its span."""
    points = []
    for outline in space:
        points += [tuple(p) for p in outline.get_points("xy")]
        for arc in (v for v in outline.virtual_entities() if v.dxftype() == "ARC"):
            (cx, cy, _), r = arc.dxf.center, arc.dxf.radius
            start, sweep = arc.dxf.start_angle, (arc.dxf.end_angle - arc.dxf.start_angle) % 360
            inside = [a for a in range(-360, 721, 90) if start < a < start + sweep]
            points += [(cx + r * math.cos(math.radians(a)), cy + r * math.sin(math.radians(a))) for a in inside]
    points = np.array(points)
    return np.array([points.min(axis=0), points.max(axis=0)])


def test_the_gds_polygons_stay_within_the_chord_error_of_the_arcs(tmp_path):
    cell = read_gds(gds_bytes(fabrication(flexmech.load(GRIPPER))), tmp_path)
    by_layer = {name: [p for p in cell.polygons if p.layer == number] for name, number in GDS_LAYERS.items()}
    assert [len(by_layer[name]) for name in ("bodies", "flexures", "anchors", "deformed")] == [3, 4, 1, 0]
    for polygon, element in zip(by_layer["flexures"], GRIPPER["elements"].values()):
        centre, r = np.array(element["center"]), element["radius"]
        offsets = polygon.points - centre
        distance = np.hypot(*offsets.T)
        grid = 1e-6  # mm: the GDS database unit, 1e-6 of the length unit
        assert distance.min() >= r - H / 2 - CHORD_ERROR - grid and distance.max() <= r + H / 2 + grid
        slack = 1e-3  # deg: a 1e-6 mm grid at 0.2 mm turns a vertex by up to 3e-4 deg
        turned = (np.degrees(np.arctan2(offsets[:, 1], offsets[:, 0])) - element["start_angle"] + slack) % 360 - slack
        assert turned.min() == pytest.approx(0.0, abs=slack) and turned.max() == pytest.approx(
            element["arc_angle"], abs=slack
        )
    (x0, y0), (x1, y1) = cell.bounding_box()
    assert [x0, y0, x1, y1] == pytest.approx([*expected_box()[0], *expected_box()[1]], abs=2 * CHORD_ERROR)


def test_a_link_is_drawn_its_width_apart_and_a_general_section_is_refused():
    document = json.loads((EXAMPLES / "grasper_shape.json").read_text())
    mech = flexmech.load(document)
    drawn = fabrication(mech)
    links = [o for o in drawn.on("flexures") if o.kind == "link"]
    assert len(links) == sum(e["type"] == "link" for e in document["elements"].values()) >= 1
    loop = links[0].points
    n = len(loop) // 2
    widths = np.hypot(*(loop[:n] - loop[::-1][:n]).T)
    section = next(iter(document["sections"].values()))
    assert widths == pytest.approx(np.full(n, mech.value(f"/sections/{next(iter(document['sections']))}/h")), rel=1e-9)
    assert section is not None
    with pytest.raises(flexmech.MechanismError) as info:
        fabrication(flexmech.load("cantilever"))
    assert info.value.pointer == "/elements/beam/section" and "no in-plane width h" in info.value.problem


def test_the_command_writes_both_files_twice_and_says_what_is_missing(tmp_path):
    runner = CliRunner()
    for k in range(2):
        done = runner.invoke(
            app,
            [
                "drawing",
                "gripper",
                "--dxf",
                str(tmp_path / f"{k}.dxf"),
                "--gds",
                str(tmp_path / f"{k}.gds"),
                "--deformed",
            ],
            env=ENV,
        )
        assert done.exit_code == 0, done.output
        assert "3 bodies, 1 anchors, 4 flexures, 4 deformed; length unit mm" in done.output
    assert (
        (tmp_path / "0.dxf").read_bytes().count(b"LWPOLYLINE")
        == (tmp_path / "1.dxf").read_bytes().count(b"LWPOLYLINE")
        == 12
    )
    thicker = runner.invoke(
        app, ["drawing", "gripper", "--dxf", str(tmp_path / "t.dxf"), "--set", "/sections/flexure/h=6um"], env=ENV
    )
    assert thicker.exit_code == 0, thicker.output
    arcs = [
        v.dxf.radius
        for e in read_dxf((tmp_path / "t.dxf").read_bytes()).modelspace().query('LWPOLYLINE[layer=="flexures"]')
        for v in e.virtual_entities()
        if v.dxftype() == "ARC"
    ]
    assert min(arcs) == pytest.approx(0.197, abs=1e-12)  # an optimized design's width, applied
    none = runner.invoke(app, ["drawing", "gripper"], env=ENV)
    assert none.exit_code == 2 and "give --dxf OUT.dxf, --gds OUT.gds or both" in none.output


def test_over_http_with_a_hostile_name(api_server):
    hostile = json.loads(json.dumps(GRIPPER))
    hostile["name"] = '../../etc/passwd"\r\nX-Evil: 1\n<script>alert(1)</script>'
    hostile["bodies"]["in\nput ARC"] = hostile["bodies"].pop("input")
    for element in hostile["elements"].values():
        for end in ("from", "to"):
            element[end] = "in\nput ARC" if element[end] == "input" else element[end]
    hostile["loads"]["actuation"]["body"] = "in\nput ARC"
    url = api_server.url + "/v1/drawings/fabrication"
    dxf = httpx.post(url, json={"document": hostile, "format": "dxf"}, timeout=60)
    gds = httpx.post(url, json={"document": hostile, "format": "gds", "deformed": True}, timeout=60)
    bad = httpx.post(url, json={"example": "gripper", "chord_error": 0}, timeout=60)
    assert dxf.status_code == gds.status_code == 200, dxf.text
    assert dxf.headers["content-disposition"] == 'attachment; filename="etc_passwd_X-Evil_1_script_alert_1_script.dxf"'
    assert b"passwd" not in dxf.content and b"script" not in dxf.content and b"in\nput" not in dxf.content
    assert sorted({e.dxf.layer for e in read_dxf(dxf.content).modelspace()}) == ["anchors", "bodies", "flexures"]
    assert gds.content[:4] == b"\x00\x06\x00\x02" and b"script" not in gds.content  # a GDSII HEADER record
    assert bad.status_code == 422 and bad.json()["error"]["pointer"] == "/chord_error"
