"""C literals of Python values, as the exported files are filled with them."""

from __future__ import annotations

from typing import Iterable, Sequence

import numpy as np

#: numbers per line of a long C array
PER_LINE = 16


def c_string(s: str) -> str:
    """A C string literal of any text: printable ASCII as is (``?`` escaped: no trigraphs),
    every other byte of its UTF-8 as a three-digit octal escape."""
    out = []
    for byte in s.encode("utf-8", "surrogatepass"):
        c = chr(byte)
        if c in '"\\?':
            out.append("\\" + c)
        elif 32 <= byte < 127:
            out.append(c)
        else:
            out.append(f"\\{byte:03o}")
    return '"' + "".join(out) + '"'


def c_double(x: float) -> str:
    """A double as a C literal that reads back exactly (Python's repr: ``1e-12``, ``600.0``)."""
    return repr(float(x))


def c_doubles(values: np.ndarray) -> str:
    """An initializer of doubles (``{0.0}`` for none: C has no empty one)."""
    if not len(values):
        return "{0.0}"
    return "{" + ", ".join(f"{float(v):.17g}" for v in values) + "}"


def c_names(names: Sequence[str]) -> str:
    """An initializer of C strings (``{0}`` for none)."""
    return "{" + (", ".join(c_string(n) for n in names) or "0") + "}"


def c_items(items: Iterable[str]) -> str:
    """The items of a long initializer, without its braces: :data:`PER_LINE` a line
    (``0`` for none: C has no empty initializer)."""
    items = list(items)
    lines = [", ".join(items[i:i + PER_LINE]) for i in range(0, len(items), PER_LINE)]
    return ",\n    ".join(lines) or "0"


def c_ints(values: np.ndarray) -> str:
    """The items of an initializer of ints (:func:`c_items`)."""
    return c_items(str(int(v)) for v in np.ravel(values))
