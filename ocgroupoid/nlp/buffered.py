"""Calls of a CasADi Function on numpy vectors through its buffer: no conversion to DM.

A plain call ``solver(x0=..., lbx=...)`` converts every numpy input to a ``DM`` and every
output back (about 85 ns per entry: 0.5 ms of a 3.6 ms fatrop solve of so3 at N = 64, for
six vectors of up to 826 entries). ``Function.buffer()`` instead reads the inputs from and
writes the outputs to memory the caller owns. :class:`Buffered` keeps one buffer per process
and thread (a forked helper, :mod:`~ocgroupoid.nlp.isolated`, makes its own) with
preallocated outputs, and returns copies of them.
"""

from __future__ import annotations

import os
import threading
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np


@dataclass
class _Buffer:
    """One Function buffer: its trigger and the arrays its outputs are written to."""

    buffer: Any
    trigger: Any
    outputs: dict[str, np.ndarray]


class Buffered:
    """``call(**inputs) -> {output name: array}`` of a Function with dense inputs and outputs;
    an input left out takes the Function's default (e.g. nlpsol's ``lbx = -inf``)."""

    def __init__(self, fn: ca.Function) -> None:
        self.fn = fn
        self.names = list(fn.name_in())
        self.sizes = [fn.nnz_in(i) for i in range(fn.n_in())]
        self.defaults = [np.full(n, fn.default_in(i)) for i, n in enumerate(self.sizes)]
        self._buffers: dict[tuple[int, int], _Buffer] = {}
        self._last: _Buffer | None = None

    def _buffer(self) -> _Buffer:
        """The buffer of this process and thread, its outputs bound to arrays of their own."""
        key = (os.getpid(), threading.get_ident())
        if key not in self._buffers:
            buffer, trigger = self.fn.buffer()
            outputs = {name: np.zeros(self.fn.nnz_out(i))
                       for i, name in enumerate(self.fn.name_out())}
            for i, out in enumerate(outputs.values()):
                buffer.set_res(i, memoryview(out))  # type: ignore[arg-type, call-arg]
            self._buffers[key] = _Buffer(buffer, trigger, outputs)
        return self._buffers[key]

    def __call__(self, **inputs: Any) -> dict[str, np.ndarray]:
        unknown = set(inputs) - set(self.names)
        if unknown:
            raise TypeError(f"{self.fn.name()} has no input {sorted(unknown)}; its inputs are "
                            f"{self.names}")
        b = self._buffer()
        held = []  # the arrays the buffer reads, alive until the call returns
        for i, (name, size) in enumerate(zip(self.names, self.sizes)):
            value = inputs.get(name)
            arr = self.defaults[i] if value is None else \
                np.ascontiguousarray(np.asarray(value, dtype=float).ravel())
            if arr.size != size:
                raise ValueError(f"{self.fn.name()}: input {name} has {arr.size} entries, "
                                 f"expected {size}")
            held.append(arr)
            b.buffer.set_arg(i, memoryview(arr))  # type: ignore[arg-type]
        b.trigger()
        self._last = b
        return {name: out.copy() for name, out in b.outputs.items()}

    def stats(self) -> dict[str, Any]:
        """The statistics of the last call (``Function.stats`` of its buffer's memory)."""
        if self._last is None:
            raise RuntimeError(f"{self.fn.name()} has not been called")
        return dict(self._last.buffer.stats())
