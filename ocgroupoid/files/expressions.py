"""Expression strings of problem files -> CasADi graphs, through a whitelist (never ``eval``).

The string is parsed by Python's ``ast`` in expression mode and every node is checked: numbers,
declared symbols, the operators ``+ - * / ** @`` and unary minus, indexing with integer
constants (``Omega[0]``, ``q[1:3]``), lists (``[a, b, c]`` is a column) and calls of the
functions in :data:`FUNCTIONS`. Anything else — attribute access, imports, lambdas,
comprehensions, keywords, strings, names that were not declared — is rejected with a message
that names the construct.

What CasADi would only find out later (or never) is checked here, at parse time, and named:
indices and slices within the length of what they index, the shapes of the operands of every
operator and function, and the arithmetic of constants (division by zero, overflow, complex
or undefined results: every constant intermediate must be a finite real number). A long sum
``a + b + c + ...`` is folded in a loop, not by recursion.
"""

from __future__ import annotations

import ast
import difflib
import math
from typing import Any, Callable, Mapping

import casadi as ca
import numpy as np

from ..errors import ConfigError

Value = Any  # a Python float (a constant) or a casadi.SX


def _norm(x: Any) -> Any:
    return ca.norm_2(x)


FUNCTIONS: dict[str, tuple[Callable[..., Any], int]] = {
    "sin": (ca.sin, 1), "cos": (ca.cos, 1), "tan": (ca.tan, 1),
    "asin": (ca.asin, 1), "acos": (ca.acos, 1), "atan": (ca.atan, 1), "atan2": (ca.atan2, 2),
    "sinh": (ca.sinh, 1), "cosh": (ca.cosh, 1), "tanh": (ca.tanh, 1),
    "exp": (ca.exp, 1), "log": (ca.log, 1), "sqrt": (ca.sqrt, 1), "abs": (ca.fabs, 1),
    "dot": (ca.dot, 2), "cross": (ca.cross, 2), "norm": (_norm, 1), "sumsqr": (ca.sumsqr, 1),
    "sum": (ca.sum1, 1), "diag": (ca.diag, 1), "transpose": (ca.transpose, 1),
    "min": (ca.fmin, 2), "max": (ca.fmax, 2),
}
CONSTANTS = {"pi": float(np.pi), "e": float(np.e)}
ELEMENTWISE = {"atan2", "min", "max"}  # two arguments of one shape (or a scalar)

_BINARY = {ast.Add: lambda a, b: a + b, ast.Sub: lambda a, b: a - b,
           ast.Mult: lambda a, b: a * b, ast.Div: lambda a, b: a / b,
           ast.Pow: lambda a, b: a ** b, ast.MatMult: lambda a, b: ca.mtimes(a, b)}
_SYMBOL = {ast.Add: "+", ast.Sub: "-", ast.Mult: "*", ast.Div: "/", ast.Pow: "**",
           ast.MatMult: "@"}
_UNARY = {ast.USub: lambda a: -a, ast.UAdd: lambda a: a}
_CASADI_ERRORS = (RuntimeError, NotImplementedError, TypeError, ValueError)


def shape(v: Value) -> tuple[int, int]:
    """Rows and columns of a compiled value (a constant is 1 x 1)."""
    return (1, 1) if isinstance(v, float) else (v.size1(), v.size2())


def _shown(s: tuple[int, int]) -> str:
    return "a scalar" if s == (1, 1) else f"{s[0]}x{s[1]}"


def _text(node: ast.AST, limit: int = 60) -> str:
    """The source of ``node``, shortened for messages."""
    try:
        text = ast.unparse(node)
    except RecursionError:  # pragma: no cover - nodes this deep are refused earlier
        text = type(node).__name__
    return text if len(text) <= limit else text[: limit - 3] + "..."


class _Compiler:
    def __init__(self, symbols: Mapping[str, Any], where: str) -> None:
        self.symbols, self.where = symbols, where

    def fail(self, node: ast.AST, what: str, fix: str) -> ConfigError:
        col = getattr(node, "col_offset", None)
        at = f" (column {col + 1})" if col is not None else ""
        return ConfigError(f"{self.where}: {what}{at}; {fix}")

    def __call__(self, node: ast.AST) -> Value:
        method = getattr(self, f"_{type(node).__name__}", None)
        if method is None:
            raise self.fail(node, f"{type(node).__name__} is not allowed in an expression",
                            "use numbers, declared symbols, + - * / ** @, indexing and the "
                            f"functions {', '.join(sorted(FUNCTIONS))}")
        return method(node)

    # -- values are finite: constants checked where they are made -------------------------

    def finite(self, node: ast.AST, value: Value) -> Value:
        """``value``, refused when it is constant and not a finite real number."""
        if isinstance(value, complex):
            raise self.fail(node, f"{_text(node)} has no real value (a complex result)",
                            "a negative base needs an integer exponent")
        if isinstance(value, float):
            numbers = np.array([value])
        elif value.is_constant():
            numbers = np.array(ca.evalf(value)).ravel()
        else:
            return value
        if not np.all(np.isfinite(numbers)):
            kind = "infinite (it overflows)" if np.any(np.isinf(numbers)) else "undefined (NaN)"
            raise self.fail(node, f"{_text(node)} is {kind}", "write a finite expression")
        return value

    def call(self, node: ast.AST, fn: Callable[..., Any], *args: Value) -> Value:
        """``fn(*args)``, CasADi's and Python's arithmetic errors named at ``node``."""
        try:
            with np.errstate(all="ignore"):
                value = fn(*args)
        except ZeroDivisionError:
            raise self.fail(node, f"{_text(node)} divides by zero", "fix the divisor") from None
        except OverflowError:
            raise self.fail(node, f"{_text(node)} overflows (beyond 1.8e+308)",
                            "write a smaller number") from None
        except _CASADI_ERRORS as err:
            reason = str(err).strip().splitlines()[-1][:160] if str(err).strip() else ""
            raise self.fail(node, f"{_text(node)} cannot be evaluated ({reason})",
                            "check the shapes and values of its arguments") from None
        if isinstance(value, ca.DM):
            value = ca.SX(value)
        return self.finite(node, value)

    # -- leaves ---------------------------------------------------------------------------

    def _Expression(self, node: ast.Expression) -> Value:
        return self(node.body)

    def _Constant(self, node: ast.Constant) -> Value:
        if isinstance(node.value, bool) or not isinstance(node.value, (int, float)):
            raise self.fail(node, f"the constant {node.value!r} is not a number",
                            "only numbers may appear as constants")
        try:
            value = float(node.value)
        except OverflowError:
            digits = int(abs(int(node.value)).bit_length() * 0.30103) + 1  # only ints overflow
            raise self.fail(node, f"the integer of about {digits} digits is too large for a "
                            "float (beyond 1.8e+308)", "write a smaller number") from None
        if math.isinf(value):
            raise self.fail(node, f"the number {_text(node)} is too large for a float (beyond "
                            "1.8e+308)", "write a smaller number")
        return value

    def _Name(self, node: ast.Name) -> Value:
        if node.id in self.symbols:
            value = self.symbols[node.id]
            return value if isinstance(value, float) else ca.SX(value)
        if node.id in CONSTANTS:
            return CONSTANTS[node.id]
        if node.id in FUNCTIONS:
            raise self.fail(node, f"{node.id} is a function", f"call it: {node.id}(...)")
        known = sorted(self.symbols) + sorted(CONSTANTS)
        close = difflib.get_close_matches(node.id, known + sorted(FUNCTIONS), 1)
        hint = f"did you mean {close[0]!r}? " if close else ""
        raise self.fail(node, f"unknown name {node.id!r}",
                        f"{hint}declared symbols are {', '.join(known)}")

    # -- operators --------------------------------------------------------------------------

    def _BinOp(self, node: ast.BinOp) -> Value:
        chain = []  # a + b + c + ... is BinOp(BinOp(a, b), c): fold the left spine in a loop
        left: ast.AST = node
        while isinstance(left, ast.BinOp):
            chain.append(left)
            left = left.left
        value = self(left)
        for op in reversed(chain):
            value = self.binary(op, value, self(op.right))
        return value

    def binary(self, node: ast.BinOp, a: Value, b: Value) -> Value:
        kind = type(node.op)
        if kind not in _BINARY:
            raise self.fail(node, f"the operator {type(node.op).__name__} is not allowed",
                            "use + - * / ** or @")
        sa, sb = shape(a), shape(b)

        def operands() -> str:  # only on failure: the text of a long sum is long
            return f"{_text(node.left, 30)} ({_shown(sa)}) {_SYMBOL[kind]} " \
                   f"{_text(node.right, 30)} ({_shown(sb)})"

        if kind is ast.MatMult:
            if sa[1] != sb[0]:
                raise self.fail(node, f"{operands()}: a matrix product needs as many columns on "
                                "the left as rows on the right",
                                "use dot(a, b) for two vectors, * for a scalar factor")
            return self.call(node, _BINARY[kind], ca.SX(a), ca.SX(b))
        if sa != sb and (1, 1) not in (sa, sb):
            raise self.fail(node, f"{operands()}: the shapes differ",
                            "give both sides the same length, or make one a scalar")
        if kind is ast.Div and self.constant_zero(b):
            raise self.fail(node, f"{_text(node)} divides by zero", "fix the divisor")
        if kind is ast.Pow and isinstance(a, float) and isinstance(b, float) and a < 0 \
                and not b.is_integer():
            raise self.fail(node, f"{_text(node)} has no real value ({a:g} to a non-integer "
                            "power)", "a negative base needs an integer exponent")
        return self.call(node, _BINARY[kind], a, b)

    @staticmethod
    def constant_zero(v: Value) -> bool:
        """True when ``v`` is a constant with a zero entry."""
        if isinstance(v, float):
            return v == 0.0
        return bool(v.is_constant() and np.any(np.array(ca.evalf(v)) == 0.0))

    def _UnaryOp(self, node: ast.UnaryOp) -> Value:
        ops = []
        inner: ast.AST = node
        while isinstance(inner, ast.UnaryOp):
            if type(inner.op) not in _UNARY:
                raise self.fail(inner, f"the operator {type(inner.op).__name__} is not allowed",
                                "use unary minus")
            ops.append(_UNARY[type(inner.op)])
            inner = inner.operand
        value = self(inner)
        for op in reversed(ops):
            value = op(value)
        return value

    def _Call(self, node: ast.Call) -> Value:
        if not isinstance(node.func, ast.Name) or node.func.id not in FUNCTIONS:
            name = node.func.id if isinstance(node.func, ast.Name) else _text(node.func)
            raise self.fail(node, f"{name!r} is not an allowed function",
                            f"allowed: {', '.join(sorted(FUNCTIONS))}")
        if node.keywords:
            raise self.fail(node, "keyword arguments are not allowed", "pass arguments by position")
        name = node.func.id
        fn, arity = FUNCTIONS[name]
        if len(node.args) != arity:
            raise self.fail(node, f"{name} takes {arity} argument(s), got "
                            f"{len(node.args)}", "fix the call")
        args = [self(a) for a in node.args]
        shapes = [shape(a) for a in args]

        def shown() -> str:
            return ", ".join(f"{_text(a, 30)} ({_shown(s)})" for a, s in zip(node.args, shapes))

        if name == "cross" and not (shapes[0] == shapes[1] and sorted(shapes[0]) == [1, 3]):
            raise self.fail(node, f"cross needs two 3-vectors of one shape, got {shown()}",
                            "pass two vectors of 3 components, e.g. cross(Omega, [0, 0, 1])")
        if name == "dot" and shapes[0] != shapes[1]:
            raise self.fail(node, f"dot needs two arguments of one shape, got {shown()}",
                            "give both the same length")
        if name in ELEMENTWISE and shapes[0] != shapes[1] and (1, 1) not in shapes:
            raise self.fail(node, f"{name} needs arguments of one shape (or a scalar), got "
                            f"{shown()}", "give both the same length")
        if name == "diag" and 1 not in shapes[0] and shapes[0][0] != shapes[0][1]:
            raise self.fail(node, f"diag needs a vector or a square matrix, got {shown()}",
                            "pass a vector (its diagonal matrix) or a square matrix")
        return self.call(node, fn, *[ca.SX(a) for a in args])

    def _List(self, node: ast.List) -> Value:
        if not node.elts:
            raise self.fail(node, "an empty list", "write at least one component")
        parts = [self(e) for e in node.elts]
        widths = {shape(p)[1] for p in parts}
        if len(widths) > 1:
            raise self.fail(node, f"the components of {_text(node)} have different numbers of "
                            "columns", "stack scalars or columns of one width")
        return self.call(node, ca.vertcat, *[ca.SX(p) for p in parts])

    _Tuple = _List

    # -- indexing ---------------------------------------------------------------------------

    def _Subscript(self, node: ast.Subscript) -> Value:
        base = self(node.value)
        what = _text(node.value, 30)
        if isinstance(base, float):
            raise self.fail(node, f"{what} is a number and has no components to index",
                            "drop the index")
        n = base.numel()
        index = node.slice
        if isinstance(index, ast.Tuple):
            return self._entry(node, base, index.elts)
        if isinstance(index, ast.Slice):
            lo, hi, step = (self._index(p) if p is not None else None
                            for p in (index.lower, index.upper, index.step))
            if step == 0:
                raise self.fail(node, f"{_text(node)}: a slice step cannot be zero",
                                "write a step of 1 or more, or leave it out (q[0:3])")
            picked = list(range(*slice(lo, hi, step).indices(n)))
            if not picked:
                raise self.fail(node, f"{_text(node)} selects no component of {what}, which "
                                f"has {n}", f"choose indices within 0..{n - 1}")
            if base.size2() == 1 or base.size1() == 1:
                return base[picked]
            return ca.vertcat(*[base[i] for i in picked])
        i = self._index(index)
        if not -n <= i < n:
            raise self.fail(node, f"{_text(node)}: index {i} is out of range for {what}, which "
                            f"has {n} component{'s' if n != 1 else ''}",
                            f"use 0..{n - 1} (or -{n}..-1 from the end)" if n else
                            f"{what} is empty")
        return base[i % n]

    def _entry(self, node: ast.Subscript, base: Any, parts: list[ast.expr]) -> Value:
        """``M[i, j]``, ``M[0:3, 3]``: rows and columns of a matrix (a rotation's 3x3, a
        pose's 4x4), each an integer or a slice within the matrix's size."""
        what = _text(node.value, 30)
        if len(parts) != 2:
            raise self.fail(node, f"{_text(node)}: a matrix takes two indices [row, column]",
                            "write e.g. R[0, 2] or g[0:3, 3]")
        picked = []
        for p, size, axis in zip(parts, (base.size1(), base.size2()), ("row", "column")):
            if isinstance(p, ast.Slice):
                lo, hi, step = (self._index(x) if x is not None else None
                                for x in (p.lower, p.upper, p.step))
                if step == 0:
                    raise self.fail(node, f"{_text(node)}: a slice step cannot be zero",
                                    "write a step of 1 or more, or leave it out")
                rng = list(range(*slice(lo, hi, step).indices(size)))
            else:
                i = self._index(p)
                if not -size <= i < size:
                    raise self.fail(node, f"{_text(node)}: {axis} {i} is out of range for "
                                    f"{what}, which has {size} {axis}s",
                                    f"use 0..{size - 1}")
                rng = [i % size]
            if not rng:
                raise self.fail(node, f"{_text(node)} selects no {axis} of {what}",
                                f"choose {axis}s within 0..{size - 1}")
            picked.append(rng)
        return base[picked[0], picked[1]]

    def _index(self, node: ast.AST) -> int:
        value = node.value if isinstance(node, ast.Constant) else None
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub) and \
                isinstance(node.operand, ast.Constant):
            value = -node.operand.value if isinstance(node.operand.value, int) else None
        if not isinstance(value, int) or isinstance(value, bool):
            raise self.fail(node, "indices must be integer constants", "write e.g. Omega[0]")
        return value

    def _Attribute(self, node: ast.Attribute) -> Value:
        raise self.fail(node, f"attribute access '.{node.attr}' is not allowed",
                        "use the listed functions instead of methods or modules")


def compile_expression(text: Any, symbols: Mapping[str, Any], where: str) -> Any:
    """The CasADi expression of ``text`` over ``symbols`` (``where`` names the key for errors)."""
    if isinstance(text, (int, float)) and not isinstance(text, bool):
        try:
            value = float(text)
        except OverflowError:
            raise ConfigError(f"{where}: the number is too large for a float (beyond "
                              "1.8e+308); write a smaller number") from None
        if not math.isfinite(value):
            raise ConfigError(f"{where}: {text!r} is not finite; write a finite number")
        return ca.SX(value)
    if not isinstance(text, str):
        raise ConfigError(f"{where}: an expression is a string, got {text!r}")
    if "__" in text:
        raise ConfigError(f"{where}: names with double underscores (such as __import__) are "
                          "never allowed; write the formula with declared symbols")
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except SyntaxError as err:
        raise ConfigError(f"{where}: not a valid expression ({err.msg} at column "
                          f"{err.offset}): {text[:80]!r}") from None
    except (RecursionError, MemoryError):
        raise ConfigError(f"{where}: the expression is nested or chained too deeply for the "
                          "parser (a sum of a few thousand terms at most); shorten it") from None
    try:
        return ca.SX(_Compiler(symbols, where)(tree))
    except RecursionError:
        raise ConfigError(f"{where}: the expression is nested too deeply (brackets or "
                          "functions within each other); shorten it") from None
