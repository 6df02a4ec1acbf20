"""Drawings for fabrication (issue 51, acceptance 4): the gripper's DXF and GDS read back with
ezdxf and gdstk: one closed outline per body and flexure on its layer, each curved flexure's arcs
of radius r +- h/2 over the document's arc angle, the bounding box the document's geometry makes;
links (a tapered one too) their width apart; bodies around what they carry; a chord error too
fine refused with one that fits, far coordinates kept in GDSII's integers; the command run twice,
with an optimize report's design; over HTTP, with hostile names kept out of the files and the
file name."""

from __future__ import annotations

import copy
import io
import json
import math
import re

import ezdxf
import gdstk
import httpx
import numpy as np
import pytest
from conftest import EXAMPLES
from matplotlib.path import Path as Polygon
from typer.testing import CliRunner

import flexmech
from flexmech.api.cli import app
from flexmech.service.drawings import fabrication_costs
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


def expected_box(document: dict = GRIPPER) -> np.ndarray:
    """[[xmin, ymin], [xmax, ymax]] from the document: each flexure's annular sector (its arcs'
    ends and the axis directions inside its span) and each body's attachment points grown by its
    margin (a convex hull grown by a disc reaches exactly its points' box plus the margin)."""
    points = []
    for element in document["elements"].values():
        (cx, cy), r, start, sweep = element["center"], element["radius"], element["start_angle"], element["arc_angle"]
        angles = [start, start + sweep] + [a for a in range(-360, 721, 90) if start < a < start + sweep]
        points += [
            (cx + rr * math.cos(math.radians(a)), cy + rr * math.sin(math.radians(a)))
            for a in angles
            for rr in (r - H / 2, r + H / 2)
        ]
    drawing = mechanism_drawing(flexmech.load(document))
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
        middles = (polygon.points + np.roll(polygon.points, -1, axis=0)) / 2 - centre  # farthest from an arc
        for reach in (distance, np.hypot(*middles.T)):  # every point of the outline, vertices rounded to the grid
            assert reach.min() >= r - H / 2 - CHORD_ERROR and reach.max() <= r + H / 2 + CHORD_ERROR
        slack = 1e-3  # deg: a 1e-6 mm grid at 0.2 mm turns a vertex by up to 3e-4 deg
        turned = (np.degrees(np.arctan2(offsets[:, 1], offsets[:, 0])) - element["start_angle"] + slack) % 360 - slack
        assert turned.min() == pytest.approx(0.0, abs=slack) and turned.max() == pytest.approx(
            element["arc_angle"], abs=slack
        )
    (x0, y0), (x1, y1) = cell.bounding_box()
    assert [x0, y0, x1, y1] == pytest.approx([*expected_box()[0], *expected_box()[1]], abs=CHORD_ERROR)


def test_links_are_drawn_their_width_apart_a_tapered_one_too_a_curved_one_within_the_chord_error():
    for name in ("grasper_shape", "gripper_ellipse_contact"):
        document = json.loads((EXAMPLES / f"{name}.json").read_text())
        drawn = fabrication(flexmech.load(document))
        space = read_dxf(dxf_bytes(drawn)).modelspace()
        links = [e for e in document["elements"].values() if e["type"] == "link"]
        flexures = space.query('LWPOLYLINE[layer=="flexures"]')
        assert len(flexures) == len(links) >= 1 and all(e.closed for e in flexures)
        assert len(space.query('LWPOLYLINE[layer=="bodies"]')) + len(
            space.query('LWPOLYLINE[layer=="anchors"]')
        ) == len(document["bodies"])
        loop = np.array(flexures[0].get_points("xy"))
        n = len(loop) // 2
        side, other = loop[:n], loop[::-1][:n]  # the two offsets of each centre-line sample
        section = document["sections"][links[0]["section"]]
        centre = (side + other) / 2
        along = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(centre, axis=0).T))])
        along /= along[-1]
        h0, h1 = section.get("h_start", section.get("h")), section.get("h_end", section.get("h"))
        assert np.hypot(*(side - other).T) == pytest.approx(h0 + (h1 - h0) * along, rel=1e-9)
    rim = json.loads((EXAMPLES / "curved_indexer.json").read_text())["elements"]["rim"]  # an arc from (0, 0) along x
    radius = rim["length"] / math.radians(
        rim["shape"]["sweep"]
    )  # 10 mm about (0, 10): its chords within the chord error
    loop = next(o for o in fabrication(flexmech.load("curved_indexer")).outlines if o.pointer == "/elements/rim").points
    n, centre = len(loop) // 2, np.array([0.0, radius])
    for side, r in ((loop[:n], radius - 0.25), (loop[n:], radius + 0.25)):  # h = 0.5 mm; the inner side first
        middles = (side[1:] + side[:-1]) / 2
        for reach in (np.hypot(*(side - centre).T), np.hypot(*(middles - centre).T)):
            assert np.abs(reach - r).max() <= CHORD_ERROR
    with pytest.raises(flexmech.MechanismError) as info:
        fabrication(flexmech.load("cantilever"))
    assert info.value.pointer == "/elements/beam/section" and "no in-plane width h" in info.value.problem


def test_a_body_is_drawn_around_what_it_carries():
    """The CSFH: the frame's hole (radius 0.2 m) and the hinge's pin (0.18 m) are inside their
    bodies' outlines, with the flexure's attachment points."""
    drawn = fabrication(flexmech.load("csfh"))
    frame, hinge = (next(o for o in drawn.outlines if o.pointer == f"/bodies/{b}") for b in ("frame", "hinge"))
    assert (frame.layer, hinge.layer) == ("anchors", "bodies")
    turn = np.linspace(0, 2 * np.pi, 360, endpoint=False)
    for outline, radius in ((frame, 0.2), (hinge, 0.18)):
        circle = radius * np.c_[np.cos(turn), np.sin(turn)]
        assert Polygon(outline.points).contains_points(circle).all()


def test_a_chord_error_too_fine_is_refused_with_one_that_fits(monkeypatch):
    mech = flexmech.load(GRIPPER)
    with pytest.raises(flexmech.MechanismError) as info:
        fabrication(mech, chord_error=1e-12)  # a grid of 1e-13 mm: 3 mm is 3e13 steps, no 32-bit integer
    assert info.value.pointer == "/chord_error" and "finer than GDSII holds" in info.value.problem
    fabrication(mech, chord_error=float(re.search(r"at least ([0-9.e+-]+)", info.value.problem)[1]))
    for limit, count in (("MAX_OUTLINE_POINTS", 200), ("MAX_POINTS", 1000)):
        monkeypatch.setattr(fabrication_costs, limit, count)
        with pytest.raises(flexmech.MechanismError) as info:
            fabrication(mech, chord_error=1e-6)
        assert info.value.pointer == "/chord_error" and re.search(
            f"more than (GDSII's )?{count}\\b", info.value.problem
        )
        enough = float(re.search(r"take at least ([0-9.e+-]+)", info.value.problem)[1])
        drawn = fabrication(mech, chord_error=enough)  # the one it says fits, fits
        sizes = [fabrication_costs.gds_vertices(o, enough - drawn.grid) for o in drawn.outlines]
        assert (max(sizes) if limit == "MAX_OUTLINE_POINTS" else sum(sizes)) <= count
        with pytest.raises(flexmech.MechanismError):
            fabrication(mech, chord_error=enough / 1.5)  # and it is about the finest that does
        monkeypatch.undo()


def test_far_coordinates_keep_their_place_in_the_gds(tmp_path):
    """5 m from the origin in mm: a grid of 1e-6 mm would need 5e12 steps; it becomes 1e-5 mm."""
    far = copy.deepcopy(GRIPPER)
    for item in (*far["bodies"].values(), *far["elements"].values()):
        key = "position" if "position" in item else "center"
        item[key] = [item[key][0] + 5000.0, item[key][1]]
    drawn = fabrication(flexmech.load(far))
    assert drawn.grid == pytest.approx(1e-5)
    path = tmp_path / "far.gds"
    path.write_bytes(gds_bytes(drawn))
    library = gdstk.read_gds(str(path))
    assert library.precision == pytest.approx(1e-8) and library.unit == pytest.approx(1e-3)
    (x0, y0), (x1, y1) = library.cells[0].bounding_box()
    assert [x0, y0, x1, y1] == pytest.approx([*expected_box(far)[0], *expected_box(far)[1]], abs=CHORD_ERROR)


def test_the_command_writes_both_files_twice_draws_a_design_and_says_what_is_wrong(tmp_path):
    runner = CliRunner()
    drawn = []
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
        space = read_dxf((tmp_path / f"{k}.dxf").read_bytes()).modelspace()
        assert sorted(e.dxf.layer for e in space if not e.closed) == ["deformed"] * 4
        drawn.append([(e.dxf.layer, e.get_points("xyb")) for e in space])
        cell = read_gds((tmp_path / f"{k}.gds").read_bytes(), tmp_path)
        assert [(p.layers, p.widths().max()) for p in cell.paths] == [((GDS_LAYERS["deformed"],), 0.0)] * 4
    assert drawn[0] == drawn[1]  # the same outlines, number for number
    report = tmp_path / "optimum.json"  # as `flexmech optimize ... --json` writes it
    report.write_text(
        json.dumps(
            {"analysis": "optimize", "design": {"/sections/flexure/h": 7}, "units": {"/sections/flexure/h": "um"}}
        )
    )
    thicker = runner.invoke(
        app, ["drawing", "gripper", "--dxf", str(tmp_path / "t.dxf"), "--design", str(report)], env=ENV
    )
    assert thicker.exit_code == 0, thicker.output
    assert arc_radii(tmp_path / "t.dxf") == pytest.approx([0.1965] * 4 + [0.2035] * 4, abs=1e-12)
    overridden = runner.invoke(
        app,
        [
            "drawing",
            "gripper",
            "--dxf",
            str(tmp_path / "t.dxf"),
            "--design",
            str(report),
            "--set",
            "/sections/flexure/h=6um",
        ],
        env=ENV,
    )
    assert overridden.exit_code == 0, overridden.output
    assert arc_radii(tmp_path / "t.dxf") == pytest.approx([0.197] * 4 + [0.203] * 4, abs=1e-12)  # --set wins
    for arguments, message in (
        ([], "--dxf: give --dxf OUT.dxf, --gds OUT.gds or both"),
        (
            ["--gds", str(tmp_path / "f.gds"), "--chord-error", "1e-12"],
            "--chord-error: 1e-12 mm is finer than GDSII holds",
        ),
        (["--dxf", str(tmp_path / "r.dxf"), "--design", str(tmp_path / "0.dxf")], "--design: "),
        (["--dxf", str(tmp_path / "no" / "r.dxf")], "--dxf: cannot write"),
        (
            ["--dxf", str(tmp_path / "d.dxf"), "--deformed", "--set", "/loads/actuation/force/1=1e9"],
            "--deformed: the equilibrium under the document's loads did not solve",
        ),
    ):
        refused = runner.invoke(app, ["drawing", "gripper", *arguments], env=ENV)
        assert refused.exit_code == 2 and message in refused.output and "Traceback" not in refused.output


def arc_radii(path) -> list[float]:
    space = read_dxf(path.read_bytes()).modelspace()
    return sorted(
        v.dxf.radius
        for e in space.query('LWPOLYLINE[layer=="flexures"]')
        for v in e.virtual_entities()
        if v.dxftype() == "ARC"
    )


# Names of bodies and elements (a name holds no '/', '~' or '.', at most 64 characters): line
# ends, NUL, DXF group codes and section markers, a layer's name, GDSII-ish bytes, escapes, markup.
HOSTILE = [
    "in\nput\r\n0\nLAYER\n2\nflexures",
    "b\x00\x06\x00\x02",
    "0\nSECTION\n2\nENTITIES",
    "anchors",
    "\x1b]0;owned\x07\x1b[2K[bold red]loud",
    "grïpper ☃ \u202e end",
    "L" * 64,
]


def hostile_gripper() -> dict:
    names = dict(zip(["frame", "input", "coupler", "follower", "a", "b", "c", "d"], HOSTILE + ["d"]))
    document = copy.deepcopy(GRIPPER)
    # 194 characters: a name's limit is 200
    document["name"] = '../../etc/passwd"\r\nX-Evil: 1\n<script>alert(1)</script>' + "x" * 140
    document["bodies"] = {names[k]: v for k, v in document["bodies"].items()}
    document["elements"] = {names[k]: v for k, v in document["elements"].items()}
    for item in (*document["elements"].values(), *document["loads"].values(), *document["outputs"].values()):
        for field in ("from", "to", "body"):
            if field in item:
                item[field] = names[item[field]]
    document.pop("sweep")
    return document


def test_over_http_with_hostile_names(api_server, tmp_path):
    url = api_server.url + "/v1/drawings/fabrication"
    hostile = hostile_gripper()
    dxf = httpx.post(url, json={"document": hostile, "format": "dxf"}, timeout=60)
    gds = httpx.post(url, json={"document": hostile, "format": "gds", "deformed": True}, timeout=60)
    assert dxf.status_code == gds.status_code == 200, dxf.text
    stem = "etc_passwd_x_evil_1_script_alert_1_script_xxxxxxxxxxxxxxxxxx"
    assert dxf.headers["content-disposition"] == f'attachment; filename="{stem}.dxf"'
    assert gds.headers["content-disposition"] == f'attachment; filename="{stem}.gds"'
    for data in (dxf.content, gds.content):
        assert b"passwd" not in data and b"script" not in data and b"owned" not in data and b"LLLL" not in data
    doc = read_dxf(dxf.content)
    layers = {layer.dxf.name for layer in doc.layers}  # ezdxf's own two and ours
    assert layers == {"0", "Defpoints", "bodies", "flexures", "anchors", "deformed"}
    assert sorted(e.dxf.layer for e in doc.modelspace()) == ["anchors"] + ["bodies"] * 3 + ["flexures"] * 4
    assert gds.content[:4] == b"\x00\x06\x00\x02"  # a GDSII HEADER record
    cell = read_gds(gds.content, tmp_path)
    assert sorted(p.layer for p in cell.polygons) == sorted(
        GDS_LAYERS[n] for n in ["anchors"] + ["bodies"] * 3 + ["flexures"] * 4
    )
    assert len(cell.paths) == 4 and {cell.name, *(c.name for c in cell.dependencies(True))} == {"MECHANISM"}
    thicker = httpx.post(
        url, json={"example": "gripper", "overrides": {"/sections/flexure/h": "6 um"}, "format": "dxf"}, timeout=60
    )
    radii = sorted(
        v.dxf.radius
        for e in read_dxf(thicker.content).modelspace().query('LWPOLYLINE[layer=="flexures"]')
        for v in e.virtual_entities()
        if v.dxftype() == "ARC"
    )
    assert radii == pytest.approx([0.197] * 4 + [0.203] * 4, abs=1e-12)
    for body, pointer in (
        ({"example": "gripper", "chord_error": 0}, "/chord_error"),
        ({"example": "gripper", "chord_error": 1e-12}, "/chord_error"),
        ({"example": "cantilever"}, "/elements/beam/section"),
        ({"example": "gripper", "format": "svg"}, "/format"),
    ):
        refused = httpx.post(url, json=body, timeout=60)
        assert refused.status_code == 422 and refused.json()["error"]["pointer"] == pointer, refused.text
