"""A compiled CasADi Function called through ctypes on numpy arrays, without copies: for
chunks of thousands of steps, converting their outputs to numpy through CasADi's DM costs
several times the steps themselves. Inputs and outputs are dense, column-major (a numpy
array of shape (columns, rows))."""

from __future__ import annotations

import ctypes
from pathlib import Path

import numpy as np

_REAL_P = ctypes.POINTER(ctypes.c_double)
_INT = ctypes.c_longlong


class NativeFunction:
    def __init__(self, library: Path, name: str, shapes_in: list[tuple[int, int]], shapes_out: list[tuple[int, int]]):
        lib = ctypes.CDLL(str(library))
        self._lib = lib  # keep loaded
        self._eval = getattr(lib, name)
        self._eval.restype = ctypes.c_int
        sizes = [_INT() for _ in range(4)]
        getattr(lib, f"{name}_work")(*[ctypes.byref(s) for s in sizes])
        n_arg, n_res, n_iw, n_w = (s.value for s in sizes)
        self.inputs = [np.zeros((cols, rows)) for rows, cols in shapes_in]
        self.outputs = [np.zeros((cols, rows)) for rows, cols in shapes_out]
        self._arg = (_REAL_P * max(n_arg, len(shapes_in)))()
        self._res = (_REAL_P * max(n_res, len(shapes_out)))()
        for k, a in enumerate(self.inputs):
            self._arg[k] = a.ctypes.data_as(_REAL_P)
        for k, a in enumerate(self.outputs):
            self._res[k] = a.ctypes.data_as(_REAL_P)
        self._iw = (_INT * max(n_iw, 1))()
        self._w = (ctypes.c_double * max(n_w, 1))()
        checkout = getattr(lib, f"{name}_checkout", None)
        self._mem = checkout() if checkout is not None else 0

    def __call__(self) -> None:
        if self._eval(self._arg, self._res, self._iw, self._w, self._mem):
            raise RuntimeError("the compiled step function failed")
