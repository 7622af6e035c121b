"""Expression strings of problem files -> CasADi graphs, through a whitelist (never ``eval``).

The string is parsed by Python's ``ast`` in expression mode and every node is checked: numbers,
declared symbols, the operators ``+ - * / ** @`` and unary minus, indexing with integer
constants (``Omega[0]``, ``q[1:3]``), lists (``[a, b, c]`` is a column) and calls of the
functions in :data:`FUNCTIONS`. Anything else — attribute access, imports, lambdas,
comprehensions, keywords, strings, names that were not declared — is rejected with a message
that names the construct.
"""

from __future__ import annotations

import ast
import difflib
from typing import Any, Callable, Mapping

import casadi as ca
import numpy as np

from ..errors import ConfigError


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

_BINARY = {ast.Add: lambda a, b: a + b, ast.Sub: lambda a, b: a - b,
           ast.Mult: lambda a, b: a * b, ast.Div: lambda a, b: a / b,
           ast.Pow: lambda a, b: a ** b, ast.MatMult: lambda a, b: ca.mtimes(a, b)}
_UNARY = {ast.USub: lambda a: -a, ast.UAdd: lambda a: a}


class _Compiler:
    def __init__(self, symbols: Mapping[str, Any], where: str) -> None:
        self.symbols, self.where = symbols, where

    def fail(self, node: ast.AST, what: str, fix: str) -> ConfigError:
        col = getattr(node, "col_offset", None)
        at = f" (column {col + 1})" if col is not None else ""
        return ConfigError(f"{self.where}: {what}{at}; {fix}")

    def __call__(self, node: ast.AST) -> Any:
        method = getattr(self, f"_{type(node).__name__}", None)
        if method is None:
            raise self.fail(node, f"{type(node).__name__} is not allowed in an expression",
                            "use numbers, declared symbols, + - * / ** @, indexing and the "
                            f"functions {', '.join(sorted(FUNCTIONS))}")
        return method(node)

    def _Expression(self, node: ast.Expression) -> Any:
        return self(node.body)

    def _Constant(self, node: ast.Constant) -> Any:
        if isinstance(node.value, bool) or not isinstance(node.value, (int, float)):
            raise self.fail(node, f"the constant {node.value!r} is not a number",
                            "only numbers may appear as constants")
        return float(node.value)

    def _Name(self, node: ast.Name) -> Any:
        if node.id in self.symbols:
            return self.symbols[node.id]
        if node.id in CONSTANTS:
            return CONSTANTS[node.id]
        if node.id in FUNCTIONS:
            raise self.fail(node, f"{node.id} is a function", f"call it: {node.id}(...)")
        known = sorted(self.symbols) + sorted(CONSTANTS)
        close = difflib.get_close_matches(node.id, known + sorted(FUNCTIONS), 1)
        hint = f"did you mean {close[0]!r}? " if close else ""
        raise self.fail(node, f"unknown name {node.id!r}",
                        f"{hint}declared symbols are {', '.join(known)}")

    def _BinOp(self, node: ast.BinOp) -> Any:
        op = _BINARY.get(type(node.op))
        if op is None:
            raise self.fail(node, f"the operator {type(node.op).__name__} is not allowed",
                            "use + - * / ** or @")
        return op(self(node.left), self(node.right))

    def _UnaryOp(self, node: ast.UnaryOp) -> Any:
        op = _UNARY.get(type(node.op))
        if op is None:
            raise self.fail(node, f"the operator {type(node.op).__name__} is not allowed",
                            "use unary minus")
        return op(self(node.operand))

    def _Call(self, node: ast.Call) -> Any:
        if not isinstance(node.func, ast.Name) or node.func.id not in FUNCTIONS:
            name = node.func.id if isinstance(node.func, ast.Name) else ast.unparse(node.func)
            raise self.fail(node, f"{name!r} is not an allowed function",
                            f"allowed: {', '.join(sorted(FUNCTIONS))}")
        if node.keywords:
            raise self.fail(node, "keyword arguments are not allowed", "pass arguments by position")
        fn, arity = FUNCTIONS[node.func.id]
        if len(node.args) != arity:
            raise self.fail(node, f"{node.func.id} takes {arity} argument(s), got "
                            f"{len(node.args)}", "fix the call")
        return fn(*(self(a) for a in node.args))

    def _List(self, node: ast.List) -> Any:
        return ca.vertcat(*(self(e) for e in node.elts))

    _Tuple = _List

    def _Subscript(self, node: ast.Subscript) -> Any:
        base = self(node.value)
        index = node.slice
        if isinstance(index, ast.Slice):
            parts = [self._index(p) if p is not None else None
                     for p in (index.lower, index.upper, index.step)]
            return base[slice(*parts)]
        return base[self._index(index)]

    def _index(self, node: ast.AST) -> int:
        value = node.value if isinstance(node, ast.Constant) else None
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub) and \
                isinstance(node.operand, ast.Constant):
            value = -node.operand.value if isinstance(node.operand.value, int) else None
        if not isinstance(value, int) or isinstance(value, bool):
            raise self.fail(node, "indices must be integer constants", "write e.g. Omega[0]")
        return value

    def _Attribute(self, node: ast.Attribute) -> Any:
        raise self.fail(node, f"attribute access '.{node.attr}' is not allowed",
                        "use the listed functions instead of methods or modules")


def compile_expression(text: Any, symbols: Mapping[str, Any], where: str) -> Any:
    """The CasADi expression of ``text`` over ``symbols`` (``where`` names the key for errors)."""
    if isinstance(text, (int, float)) and not isinstance(text, bool):
        return ca.SX(float(text))
    if not isinstance(text, str):
        raise ConfigError(f"{where}: an expression is a string, got {text!r}")
    if "__" in text:
        raise ConfigError(f"{where}: names with double underscores (such as __import__) are "
                          "never allowed; write the formula with declared symbols")
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except SyntaxError as err:
        raise ConfigError(f"{where}: not a valid expression ({err.msg} at column "
                          f"{err.offset}): {text!r}") from None
    return ca.SX(_Compiler(symbols, where)(tree))
