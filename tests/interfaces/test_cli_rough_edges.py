"""Rough edges a new user met in the command line and its figures: the planar spring's sweep
shows its force and stiffness, --stiffness prints the terms of K_T, trace draws its path,
figures label loads and elements legibly and title their axes in the axes' words, and text a
user reads names the papers. Figures are checked as matplotlib objects, before saving."""

from __future__ import annotations

import importlib.util
import itertools
import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from flexmech.api.cli import app
from flexmech.models import compile_mechanism, load_document
from flexmech.service import solve_equilibrium, sweep
from flexmech.service.drawings.plotting import configuration_figure, load_point, sweeps_figure, trace_figure
from flexmech.service.solvers.continuation import trace_path

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
GRIPPER = EXAMPLES / "gripper.json"
SPRING = EXAMPLES / "planar_spring.json"
ARCH = EXAMPLES / "snap_through_arch.json"
ACTUATION = "/loads/actuation/force/1"
CROWN_LOAD = "/loads/P/force/1"
ENV = {"COLUMNS": "200", "FORCE_COLOR": None, "TTY_COMPATIBLE": None, "NO_COLOR": "1"}

# Planar spring (README, measured): 3.2573e4 N/m at small dX; the secant at 2 um is 5.07 %
# stiffer. The thesis publishes 3.2667e4 N/m, 0.29 % above (its I is rounded).
SPRING_START_N_PER_M = 3.2573e4
SPRING_STIFFENING = 0.0507
PUBLISHED_SPRING_N_PER_M = 3.2667e4
MN_PER_UM_IN_N_PER_M = 1e3
# Snap-through arch (README): snaps through at -103.200 N, back at -36.059 N.
SNAP_THROUGH, SNAP_BACK = -103.200, -36.059


@pytest.fixture
def run():
    runner = CliRunner()
    return lambda *args: runner.invoke(app, [str(a) for a in args], env=ENV)


def _renderer(fig):
    fig.canvas.draw()
    return fig.canvas.get_renderer()


# --- 1. the planar spring's sweep ----------------------------------------------------------
def test_planar_spring_sweep_shows_force_against_displacement_and_its_stiffness(run, tmp_path):
    out = tmp_path / "spring.json"
    result = run("sweep", SPRING, "--json", out)
    assert result.exit_code == 0, result.output
    data = json.loads(out.read_text())
    assert (data["x_output"], data["y_output"]) == ("A.dx", "spring_force.Fx")
    assert "A.dx [um]" in result.stdout and "spring_force.Fx [mN]" in result.stdout
    assert "mixed models" not in result.stdout  # a spring of links has no curved-beam model

    curve = data["curves"][0]
    force = np.asarray(curve["sweep"]["outputs"]["spring_force.Fx"])
    dX = np.asarray(curve["sweep"]["values"])
    stiffness = curve["stiffness"]
    assert stiffness["unit"] == "mN/um" and stiffness["si_unit"] == "N/m"
    # the secants are the sweep's own numbers
    assert stiffness["first_step"] == pytest.approx(force[1] / dX[1], rel=1e-12)
    assert stiffness["last"] == pytest.approx(force[-1] / dX[-1], rel=1e-12)
    # against the README and the thesis
    start = stiffness["start"] * MN_PER_UM_IN_N_PER_M
    assert start == pytest.approx(SPRING_START_N_PER_M, rel=5e-5)
    assert start == pytest.approx(PUBLISHED_SPRING_N_PER_M, rel=5e-3)
    assert stiffness["last"] / stiffness["start"] - 1 == pytest.approx(SPRING_STIFFENING, abs=5e-4)
    # printed in document units and SI
    printed = " ".join(result.stdout.split())
    assert "secant stiffness spring_force.Fx / dX dx:" in printed
    assert f"{stiffness['first_step']:.6g} mN/um" in printed and "at the first step" in printed
    assert f"{stiffness['last']:.6g} mN/um" in printed and "at the last" in printed
    assert "stiffness at the start 32.5729 mN/um (3.25729e4 N/m)" in printed
    assert "is +5.07 % relative to it" in printed


def test_planar_spring_figure_draws_force_and_secant_stiffness():
    mech = compile_mechanism(load_document(SPRING))
    result = sweep(mech, "/loads/dX/dx", np.linspace(0, 2, 11))
    fig = sweeps_figure([("polysilicon", result)], "A.dx", "spring_force.Fx", "/loads/dX/dx", secant=True)
    left, right = fig.axes
    assert left.get_ylabel() == "spring_force.Fx [mN]" and left.get_title() == "spring_force.Fx against A.dx"
    assert right.get_ylabel() == "secant stiffness spring_force.Fx / dX dx [mN/um]"
    assert right.get_title() == "secant stiffness spring_force.Fx / dX dx against A.dx"
    force = np.asarray(result.outputs["spring_force.Fx"])
    np.testing.assert_allclose(left.lines[0].get_ydata(), force)
    secant = np.asarray(right.lines[0].get_ydata())
    assert math.isnan(secant[0])
    np.testing.assert_allclose(secant[1:], force[1:] / result.values[1:])
    assert np.all(np.diff(secant[1:]) > 0)  # it stiffens all the way


# --- 2. the terms of K_T -------------------------------------------------------------------
def test_solve_stiffness_prints_the_nonzero_terms_of_the_tangent(run, tmp_path):
    out = tmp_path / "k.json"
    result = run("solve", GRIPPER, "--stiffness", "--json", out)
    assert result.exit_code == 0, result.output
    stiffness = json.loads(out.read_text())["stiffness"]
    K, terms = np.asarray(stiffness["K"]), {k: np.asarray(v) for k, v in stiffness["terms"].items()}
    np.testing.assert_allclose(sum(terms.values()), K, atol=1e-9 * np.abs(K).max())
    text = result.stdout
    for title in (
        "term I of K_T (Cammarata et al. 2022",
        "term II of K_T (Cammarata et al. 2022",
        "term III of K_T (Cammarata et al. 2022",
    ):
        assert title in text
    assert (
        text.index("tangent stiffness K_T")
        < text.index("term I of K_T")
        < text.index("term II of K_T")
        < text.index("term III of K_T")
    )
    # the gripper's force acts at a reference point: no load term
    assert not terms["load"].any() and "zero term of K_T here: load" in text
    assert f"{terms['III'][2][0]:.6g}" in text.split("term III of K_T")[1]


def test_linear_model_has_no_term_three(run):
    result = run("solve", GRIPPER, "--stiffness", "--model", "linear")
    assert result.exit_code == 0, result.output
    assert "term II of K_T" in result.stdout and "term III of K_T" not in result.stdout
    assert "zero terms of K_T here: III, load" in result.stdout


# --- 3. trace --plot -----------------------------------------------------------------------
def test_trace_writes_a_plot(run, tmp_path):
    plot = tmp_path / "arch.png"
    result = run("trace", ARCH, "--path", CROWN_LOAD, "--stop", "-300", "--step", "20", "--plot", plot)
    assert result.exit_code == 0, result.output
    assert plot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert f"wrote {plot}" in " ".join(result.stdout.split())


def test_trace_plot_with_an_unknown_format_is_a_one_line_error(run, tmp_path):
    result = run("trace", ARCH, "--path", CROWN_LOAD, "--stop", "-300", "--step", "20", "--plot", tmp_path / "a.txt")
    assert result.exit_code == 2
    assert result.stderr.strip().startswith("error: --plot: cannot tell the figure format")


def test_trace_figure_dashes_the_unstable_branch_between_the_limit_points():
    mech = compile_mechanism(load_document(ARCH))
    path = trace_path(mech, CROWN_LOAD, -300.0, 20.0)
    fig = trace_figure(mech, path, "crown.dy")
    ax = fig.axes[0]
    assert ax.get_xlabel() == "crown.dy [mm]" and ax.get_ylabel() == "P force y [N]"
    solid = [line for line in ax.lines if line.get_linestyle() == "-"]
    dashed = [line for line in ax.lines if line.get_linestyle() == "--"]
    assert len(solid) == 2 and len(dashed) == 1  # loading, unstable, after snapping through
    unstable = np.asarray(dashed[0].get_ydata())
    assert unstable.min() == pytest.approx(SNAP_THROUGH, abs=1e-3)  # it begins and ends at the limits
    assert unstable.max() == pytest.approx(SNAP_BACK, abs=1e-3)
    marked = [line for line in ax.lines if line.get_marker() == "o"]
    assert sorted(float(line.get_ydata()[0]) for line in marked) == pytest.approx([SNAP_THROUGH, SNAP_BACK], abs=1e-3)
    texts = [t.get_text() for t in ax.texts]
    for lp in path.limit_points:
        assert f"{lp.kind} {lp.value:.6g} N" in texts
    legend = [t.get_text() for t in ax.get_legend().get_texts()]
    assert legend == ["stable", "unstable", "limit points"]


# --- 4a. the configuration plot ------------------------------------------------------------
def test_gripper_plot_labels_do_not_cover_each_other_and_the_load_has_an_arrow():
    mech = compile_mechanism(load_document(GRIPPER))
    result = solve_equilibrium(mech)
    fig = configuration_figure(result)
    ax = fig.axes[0]
    renderer = _renderer(fig)
    labels = {t.get_text(): t.get_window_extent(renderer) for t in ax.texts if t.get_text()}
    assert {
        "a",
        "b",
        "c",
        "d",
        "frame (fixed)",
        "input",
        "coupler",
        "follower",
        "end_effector",
        "actuation 50 uN",
    } <= set(labels)
    for (one, box), (other, other_box) in itertools.combinations(labels.items(), 2):
        assert not box.overlaps(other_box), (one, other)
    assert not labels["a"].overlaps(labels["frame (fixed)"])
    arrows = [t for t in ax.texts if getattr(t, "arrow_patch", None) is not None]
    assert len(arrows) == 1
    out = result.outputs()
    head, tail = np.asarray(arrows[0].xy), np.asarray(arrows[0].xyann)
    np.testing.assert_allclose(head, [out["bodies.input.x"], out["bodies.input.y"]])  # deformed
    assert tail[0] == pytest.approx(head[0]) and tail[1] < head[1]  # the force points up, +y


def test_loads_off_the_reference_point_are_drawn_where_they_act_in_the_deformed_state():
    data = json.loads(GRIPPER.read_text())
    data["loads"]["actuation"]["offset"] = [0.3, 0.1]  # body axes
    data["loads"]["twist"] = {"type": "moment", "body": "coupler", "moment": -2.0}
    mech = compile_mechanism(load_document(data))
    result = solve_equilibrium(mech)
    assert result.converged
    out = result.outputs()
    angle = math.radians(out["bodies.input.angle"])  # the document's angles are degrees
    expected = np.array(
        [
            out["bodies.input.x"] + 0.3 * math.cos(angle) - 0.1 * math.sin(angle),
            out["bodies.input.y"] + 0.3 * math.sin(angle) + 0.1 * math.cos(angle),
        ]
    )
    np.testing.assert_allclose(load_point(mech, "actuation", out), expected, rtol=1e-12)
    ax = configuration_figure(result).axes[0]
    arrows = [t for t in ax.texts if getattr(t, "arrow_patch", None) is not None]
    np.testing.assert_allclose(arrows[0].xy, expected, rtol=1e-12)
    moments = [line for line in ax.lines if "circlearrow" in str(line.get_marker())]
    assert len(moments) == 1 and "circlearrowright" in moments[0].get_marker()  # clockwise
    np.testing.assert_allclose(moments[0].get_xydata()[0], [out["bodies.coupler.x"], out["bodies.coupler.y"]])
    assert "twist -2 uN*mm" in [t.get_text() for t in ax.texts]


# --- 4b. the movement plot -----------------------------------------------------------------
def test_movement_plot_titles_say_what_the_axes_say():
    mech = compile_mechanism(load_document(GRIPPER))
    result = sweep(mech, ACTUATION, np.linspace(-60, 77.0346, 6))
    fig = sweeps_figure([("silicon", result)], "end_effector.x", "end_effector.y", ACTUATION)
    trajectory, force = fig.axes
    assert trajectory.get_title() == "trajectory of end_effector"
    assert force.get_ylabel() == "actuation force y [uN]"
    assert force.get_title() == "actuation force y against end_effector.x"
    assert force.get_xlabel() == "end_effector.x [mm]"
    assert "/" not in force.get_title()


# --- 4c. the comparison of materials -------------------------------------------------------
@pytest.fixture
def comparison_script(monkeypatch):
    """examples/compare_gripper_models.py as a module (registered while the test runs, as its
    dataclass needs)."""
    spec = importlib.util.spec_from_file_location("compare_gripper_models", EXAMPLES / "compare_gripper_models.py")
    module = importlib.util.module_from_spec(spec)
    monkeypatch.setitem(sys.modules, spec.name, module)
    spec.loader.exec_module(module)
    return module


def test_compare_gripper_models_shows_silicon_and_nylon_apart(comparison_script):
    script = comparison_script
    E = {m: compile_mechanism(load_document(script.MATERIALS[m])).value(f"/materials/{m}/E") for m in script.MATERIALS}
    ratio = E["nylon"] / E["silicon"]
    curves = {
        "silicon": script.material_curves("silicon", script.MATERIALS["silicon"], 4, -60.0),
        "nylon": script.material_curves("nylon", script.MATERIALS["nylon"], 4, -60.0 * ratio),
    }
    # Under loads scaled with E, both materials move alike: one would hide the other on one axes.
    for silicon, nylon in zip(curves["silicon"], curves["nylon"]):
        assert nylon.closing_force / silicon.closing_force == pytest.approx(ratio, rel=1e-6)
        np.testing.assert_allclose(nylon.x, silicon.x, atol=1e-9)
    fig = script.models_figure(curves)
    assert len(fig.axes) == 4
    for ax in fig.axes:
        material = ax.get_title().split(":")[0]
        assert material in ("silicon", "nylon")
        assert len(ax.lines) == 3  # the three models of that material only
        if "actuation force" in ax.get_title():  # each line ends where its model closes the gripper
            ends = [float(line.get_ydata()[-1]) for line in ax.lines]
            assert ends == pytest.approx([c.closing_force for c in curves[material]], rel=1e-12)
    titles = [ax.get_title() for ax in fig.axes]
    assert titles.count("silicon: end-effector trajectory") == 1 and titles.count("nylon: end-effector trajectory") == 1
    assert "Cammarata et al. 2022" in fig.get_suptitle()


# --- 5. the papers by name -----------------------------------------------------------------
def test_user_facing_text_names_the_papers(run, comparison_script):
    for command in ("solve", "sweep", "trace"):
        help_text = run(command, "--help").stdout
        assert "seed 00" not in help_text and "seed-00" not in help_text
    assert "Lan 2005 (thesis)" in load_document(SPRING).name
    script = comparison_script
    assert "Cammarata et al. 2022" in script.__doc__.splitlines()[0]
    assert "seed" not in script.__doc__
