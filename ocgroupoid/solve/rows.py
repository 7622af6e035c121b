"""The constraint rows of a solved grid, as carrying its multipliers onto another grid needs
them (:func:`~ocgroupoid.solve.multipliers.carried`): kept by a
:class:`~ocgroupoid.solve.solution.Solution`, so that ``solve(guess=solution)`` on a finer
grid starts from its multipliers too, without the NLP it was solved on.
"""

from __future__ import annotations

from dataclasses import dataclass
from weakref import WeakKeyDictionary

import numpy as np

from ..nlp.assembly import Kind
from ..nlp.transcription import Transcription


@dataclass(frozen=True)
class RowBlock:
    """One constraint block: its name and kind, its rows (m/points x columns*points, one
    column per time, :attr:`~ocgroupoid.nlp.assembly.Block.g_rows`), the times of its
    columns as fractions of T (None when it has none: a block of one column per interval
    is at their midpoints, :func:`times`) and the points of a column."""

    name: str
    kind: Kind
    g_rows: np.ndarray
    times: np.ndarray
    points: int


@dataclass(frozen=True)
class Rows:
    """A grid's NLP as its multipliers are laid out: N, its scheme, retraction and rule,
    whether its steps are phased (adaptive), its variables (the stage variables first, which
    have no bounds of their own) and its constraint blocks."""

    N: int
    method: tuple[str, str, str]
    phased: bool
    nx: int
    stage: int
    blocks: tuple[RowBlock, ...]

    @property
    def ng(self) -> int:
        """The constraint rows."""
        return sum(int(b.g_rows.size) for b in self.blocks)

    @classmethod
    def of(cls, tr: Transcription) -> Rows:
        """The rows of ``tr``'s NLP, made once per transcription: its solutions share them."""
        if tr not in _made:
            _made[tr] = cls(tr.N, (tr.disc.scheme, tr.disc.retraction, tr.disc.rule),
                            bool(tr.layout.phases), tr.nx, tr.layout.stage.size,
                            tuple(RowBlock(b.name, b.kind, b.g_rows,
                                           np.asarray(b.times, dtype=float), b.points)
                                  for b in tr.blocks))
        return _made[tr]


#: the rows of each transcription, once made
_made: WeakKeyDictionary[Transcription, Rows] = WeakKeyDictionary()


def times(block: RowBlock, N: int) -> np.ndarray | None:
    """The times of a block's columns as fractions of T: its own, or the interval midpoints
    of a block with one column per interval (the reconstruction); None when neither."""
    columns = block.g_rows.shape[1]
    if block.times.size == columns:
        return block.times
    if columns == N:
        return (np.arange(N) + 0.5) / N
    return None
