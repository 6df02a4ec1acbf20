"""A Function called on buffers it owns (service.dynamics.buffered) returns what the ordinary
call returns, in the same shapes and column-major order; a sparse Function is refused."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from flexmech.service.buffered import BufferedCall


def test_a_buffered_call_returns_what_the_ordinary_call_does():
    A, x, h = ca.MX.sym("A", 3, 4), ca.MX.sym("x", 4), ca.MX.sym("h")
    empty = ca.MX.sym("empty", 0, 5)
    fn = ca.Function("f", [A, x, h, empty], [ca.mtimes(A, x) * h, ca.sin(A).T, ca.MX.zeros(0, 5) + empty])
    call = BufferedCall(fn)
    rng = np.random.default_rng(1)
    for _ in range(3):  # the buffers are reused call after call
        args = [rng.standard_normal((3, 4)), rng.standard_normal(4), float(rng.uniform(0.5, 2)), np.zeros((0, 5))]
        got = call(*args)
        expected = [np.asarray(q) for q in fn(*args)]
        assert [g.shape for g in got] == [(3, 1), (4, 3), (0, 5)]
        for g, e in zip(got, expected):
            np.testing.assert_array_equal(g, e.reshape(g.shape))


def test_a_sparse_function_is_refused():
    x = ca.MX.sym("x", 3)
    with pytest.raises(ValueError, match="sparse input or output"):
        BufferedCall(ca.Function("diagonal", [x], [ca.diag(x)]))
