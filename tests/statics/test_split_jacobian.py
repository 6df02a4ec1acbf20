"""The split Jacobian (models.graph.split_jacobian) against CasADi's own and against finite
differences: a residual with dense rows and columns (a long link's end conditions and their
multipliers) and one without."""

from __future__ import annotations

import json

import casadi as ca
import numpy as np
from conftest import EXAMPLES

from flexmech.models import compile_mechanism, load_document
from flexmech.models.graph.assembly import _symbolic
from flexmech.models.graph.residual import residual_of
from flexmech.models.graph.split_jacobian import jacobian


def _values(K: ca.SX, z: ca.SX, p: ca.SX, at: np.ndarray, params: np.ndarray) -> np.ndarray:
    return np.asarray(ca.densify(ca.Function("K", [z, p], [K])(at, params)))


def test_dense_rows_and_columns_split_as_casadi_differentiates():
    z = ca.SX.sym("z", 60)
    local = ca.vertcat(*[z[i] ** 2 * ca.sin(z[i + 1]) for i in range(58)])  # banded
    total = ca.sum1(ca.cos(z[:58]))  # a row on everything
    lam = z[58:]  # columns in every row
    R = ca.vertcat(local + lam[0] * z[:58] + lam[1] * ca.exp(z[1:59] / 7), total, ca.sum1(z[:58] ** 3))
    p = ca.SX.sym("p", 0)
    at = np.random.default_rng(3).normal(size=60)
    split, plain = jacobian(R, z), ca.jacobian(R, z)
    assert split.sparsity() == plain.sparsity()
    np.testing.assert_allclose(_values(split, z, p, at, []), _values(plain, z, p, at, []), rtol=1e-14, atol=1e-14)


def test_a_long_links_tangent_equals_finite_differences_of_its_residual():
    doc = json.loads((EXAMPLES / "rod_free_vibration.json").read_text())
    doc["elements"]["rod"]["intervals"] = 12  # 114 unknowns: the end conditions' rows and columns are dense
    mech = compile_mechanism(load_document(doc))
    ctx, z, d, parts, applied = _symbolic(mech.structure)
    R = residual_of(ctx, parts, applied)
    pattern = ca.jacobian_sparsity(R, z)
    assert np.bincount(np.asarray(pattern.row()), minlength=R.numel()).max() > 0.9 * z.numel()  # dense rows
    K = jacobian(R, z)
    assert K.sparsity() == pattern
    at, params = 0.05 * np.random.default_rng(5).normal(size=z.numel()), mech.p()
    exact = _values(K, z, ctx.p, at, params)
    residual = ca.Function("R", [z, ctx.p], [R])
    step = 1e-6
    columns = []
    for j in range(z.numel()):
        e = np.zeros(z.numel())
        e[j] = step
        columns.append(
            (np.asarray(residual(at + e, params)) - np.asarray(residual(at - e, params))).ravel() / (2 * step)
        )
    central = np.column_stack(columns)
    assert np.abs(exact - central).max() <= 1e-6 * np.abs(exact).max()
