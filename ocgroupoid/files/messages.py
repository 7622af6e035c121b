"""pydantic's validation errors as messages that name the key, the line and the fix."""

from __future__ import annotations

import difflib
import re
from typing import Any

from pydantic import BaseModel, ValidationError
from pydantic_core import ErrorDetails

from ..errors import ConfigError
from ..model.values import short
from .source import Locator


def _fix(err: ErrorDetails, key: str, known: list[str] | None) -> str:
    """A message with the fix for one pydantic error."""
    kind, value = err["type"], err.get("input")
    ctx = err.get("ctx") or {}
    last = key.rsplit(".", 1)[-1]
    if kind == "extra_forbidden":
        close = difflib.get_close_matches(last, known or [], 1)
        hint = f" did you mean {close[0]!r}?" if close else ""
        allowed = f" keys allowed here: {', '.join(known)}" if known else " remove it"
        return f"unknown key {key!r};{hint}{allowed}"
    if kind == "missing":
        return f"missing key {key!r}; add it (see problems/ for an example)"
    if kind in ("int_type", "int_from_float", "int_parsing"):
        return f"{key} must be an integer (e.g. 64), got {short(value)}"
    if kind in ("greater_than_equal", "greater_than"):
        bound = ctx.get("ge", ctx.get("gt"))
        op = ">=" if kind == "greater_than_equal" else ">"
        return f"{key} must be {op} {bound}, got {short(value)}; raise it"
    if kind == "literal_error":
        options = [o.strip(" '") for o in str(ctx.get("expected", "")).replace(" or ", ", ")
                   .split(",")]
        close = difflib.get_close_matches(str(value), options, 1)
        hint = f" did you mean {close[0]!r}?" if close else ""
        return f"{key}: {short(value)} is not allowed;{hint} choose one of {', '.join(options)}"
    if kind in ("dict_type", "model_type", "model_attributes_type"):
        return f"{key} must be a mapping (key: value), got {short(value)}"
    if kind == "too_long":
        return (f"{key} has {ctx.get('actual_length', 'too many')} entries, at most "
                f"{ctx.get('max_length')} are allowed; drop some")
    if kind == "list_type":
        return f"{key} must be a list, e.g. [1, 2, 3], got {short(value)}"
    if kind in ("string_type",):
        return f"{key} must be text, got {short(value)}; quote it"
    if kind in ("bool_type", "bool_parsing"):
        return f"{key} must be true or false, got {short(value)}"
    if kind in ("float_type", "float_parsing", "finite_number"):
        return f"{key} must be a finite number, got {short(value)}"
    msg = str(err["msg"]).removeprefix("Value error, ")
    return f"{key}: {msg}"


def _fields_at(model: type[BaseModel], loc: tuple) -> list[str] | None:
    """Field names of the (sub)model that owns the last key of ``loc``."""
    current: Any = model
    for part in loc[:-1]:
        fields = getattr(current, "model_fields", None)
        if not fields or part not in fields:
            return None
        ann = fields[part].annotation
        current = ann if isinstance(ann, type) and issubclass(ann, BaseModel) else None
        if current is None:
            return None
    return list(getattr(current, "model_fields", {}) or [])


def validate(model: type[BaseModel], data: Any, prefix: tuple, locate: Locator) -> Any:
    """``model.model_validate(data)`` with errors that name the key, the line and the fix."""
    try:
        return model.model_validate(data if data is not None else {})
    except ValidationError as exc:
        messages = []
        for err in exc.errors():
            loc = _keys(data, err["loc"], keep_last=err["type"] == "missing")
            path = (*prefix, *loc)
            key = ".".join(map(str, path))
            message = f"{locate(*path)}: {_fix(err, key, _fields_at(model, loc))}"
            if message not in messages:
                messages.append(message)
        raise ConfigError("\n".join(messages)) from None


def _keys(data: Any, loc: tuple, keep_last: bool = False) -> tuple:
    """The keys of an error's location: pydantic's tags of validators (``function-...``) and
    of the members of a union (``Described``, ``str``, ``list[str]``) dropped, unless the data
    has such a key (or it is the missing key, ``keep_last``)."""
    out: list[Any] = []
    node = data
    for i, part in enumerate(loc):
        if isinstance(node, dict) and part in node:
            node = node[part]
        elif isinstance(node, list) and isinstance(part, int) and 0 <= part < len(node):
            node = node[part]
        elif isinstance(part, str) and _TAG.fullmatch(part) and not (
                keep_last and i == len(loc) - 1):
            continue
        else:
            node = None
        out.append(part)
    return tuple(out)


_TAG = re.compile(r"function-.*|[A-Z]\w*|str|int|float|bool|none|\w+\[.*\]")
