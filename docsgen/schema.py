"""The problem-file reference, generated from the pydantic models that validate the files.

Every key the schema accepts becomes one row (key, type, default, range, description): the
top level and its sections (:class:`~ocgroupoid.files.schema.ProblemFile`), the ``definition``
of a custom model (:class:`~ocgroupoid.files.custom.Definition`) and the ``parameters``,
``initial`` and ``final`` sections of every built-in model
(:data:`~ocgroupoid.systems.MODELS`). Nested keys are dotted (``horizon.N``); an item of a list
of sections is ``[]`` (``definition.groupoid[].type``) and an entry of a mapping of sections
``<name>`` (``definition.describe.<name>.unit``). A key without a description is an error:
the reference documents every key or the build fails.
"""

from __future__ import annotations

import json
import re
import types
from dataclasses import dataclass
from functools import partial
from typing import Annotated, Any, Iterator, Literal, Union, get_args, get_origin

import annotated_types as at
from pydantic import BaseModel, BeforeValidator
from pydantic.fields import FieldInfo
from pydantic_core import PydanticUndefined

from ocgroupoid.files.custom import Definition
from ocgroupoid.files.schema import ProblemFile
from ocgroupoid.model.values import check_vector
from ocgroupoid.systems import MODELS

#: the scalar types by the name a problem file's author knows them
NAMES = {str: "text", int: "integer", float: "number", bool: "boolean", Any: "value",
         dict: "mapping", list: "list"}


@dataclass(frozen=True)
class Row:
    """One key of the reference."""

    key: str
    type: str
    default: str
    range: str
    description: str


@dataclass(frozen=True)
class Section:
    """A table of the reference: a title, a sentence on where its keys apply, its rows."""

    title: str
    intro: str
    rows: tuple[Row, ...]


def _resolve(match: re.Match[str], scope: dict[str, Any]) -> str:
    """A Sphinx role (``:data:`~x.T_RANGE```) as its value where it names a number, a range
    or a text (``ROTATION_FORMS``), as its last name otherwise."""
    name = match.group(1).split(".")[-1]
    value = scope.get(name)
    if isinstance(value, str):
        return value
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return f"{value:g}"
    if isinstance(value, tuple) and len(value) == 2 and all(isinstance(v, float) for v in value):
        return f"[{value[0]:g}, {value[1]:g}]"
    return name


def first_sentence(doc: str | None, scope: dict[str, Any]) -> str:
    """The first sentence of a docstring on one line, roles resolved against ``scope``."""
    text = " ".join((doc or "").split())
    text = re.sub(r":\w+:`~?([\w.]+)`", lambda m: _resolve(m, scope), text)
    text = text.replace("``", "`")
    end = re.search(r"\.(\s|$)", text)
    return (text[:end.start()] if end else text).strip()


def _validator(func: Any) -> str:
    """What a ``BeforeValidator`` accepts: the vectors of :func:`vector` by their size and
    flags, any other check by its docstring's first sentence."""
    if isinstance(func, partial):
        if func.func is check_vector:
            kw = func.keywords
            flags = [", each > 0" if kw.get("positive") else "",
                     " (null components: free)" if kw.get("allow_none") else ""]
            return f"{kw['n']} numbers" + "".join(flags)
        func = func.func
    text = first_sentence(func.__doc__, func.__globals__)
    if not text:
        raise ValueError(f"the validator {func.__qualname__} has no docstring: the reference "
                         "states what it accepts from it")
    return text[0].lower() + text[1:]


#: how each annotated-types constraint reads in the reference
_BOUNDS: dict[type, Any] = {
    at.Ge: lambda m: f">= {m.ge}", at.Gt: lambda m: f"> {m.gt}",
    at.Le: lambda m: f"<= {m.le}", at.Lt: lambda m: f"< {m.lt}",
    at.MinLen: lambda m: f"at least {m.min_length} items",
    at.MaxLen: lambda m: f"at most {m.max_length} items",
}


def _constraints(meta: list[Any]) -> list[str]:
    """The range a field's metadata states (``ge``, ``le``, lengths, validators)."""
    return [_validator(m.func) if isinstance(m, BeforeValidator) else _BOUNDS[type(m)](m)
            for m in meta if isinstance(m, BeforeValidator) or type(m) in _BOUNDS]


def type_text(tp: Any) -> tuple[str, list[str]]:
    """The type of an annotation in words, and the ranges its ``Annotated`` parts state."""
    origin = get_origin(tp)
    if origin is Annotated:
        base, *meta = get_args(tp)
        flat: list[Any] = []
        for m in meta:  # Field(ge=2) inside Annotated arrives as a FieldInfo
            flat.extend(m.metadata if isinstance(m, FieldInfo) else [m])
        text, ranges = type_text(base)
        return text, ranges + _constraints(flat)
    if origin in (Union, types.UnionType):
        args = get_args(tp)
        parts = [type_text(a) for a in args if a is not type(None)]
        text = " or ".join(p[0] for p in parts) + (" or null" if type(None) in args else "")
        return text, [r for p in parts for r in p[1]]
    if origin is Literal:
        return "one of " + ", ".join(f"`{json.dumps(a) if isinstance(a, str) else a}`"
                                     .replace('"', "") for a in get_args(tp)), []
    if origin is list:
        item, ranges = type_text(get_args(tp)[0])
        return f"list of {item}", ranges
    if origin is dict:
        key, value = (type_text(a)[0] for a in get_args(tp))
        return f"mapping of {key} to {value}", []
    if isinstance(tp, type) and issubclass(tp, BaseModel):
        return "section", []
    if tp in NAMES:
        return NAMES[tp], []
    raise ValueError(f"no words for the type {tp!r} in the reference; add it to "
                     "docsgen.schema.NAMES")


def nested(tp: Any) -> tuple[type[BaseModel], str] | None:
    """The section model an annotation holds, and how its keys continue the path: ``.``
    (a section), ``[].`` (a list of sections) or ``.<name>.`` (a mapping of sections)."""
    origin = get_origin(tp)
    if isinstance(tp, type) and issubclass(tp, BaseModel):
        return tp, "."
    if origin is Annotated:
        return nested(get_args(tp)[0])
    if origin in (Union, types.UnionType):
        found = [n for n in (nested(a) for a in get_args(tp)) if n is not None]
        return found[0] if found else None
    if origin is list:
        inner = nested(get_args(tp)[0])
        return (inner[0], "[].") if inner else None
    if origin is dict:
        inner = nested(get_args(tp)[1])
        return (inner[0], ".<name>.") if inner else None
    return None


def _value(v: Any) -> str:
    """A default as a problem file writes it."""
    if isinstance(v, BaseModel):
        return "(its keys' defaults)"
    return f"`{json.dumps(v)}`"


def default_text(field: FieldInfo) -> str:
    """``required``, or the default a left-out key takes."""
    if field.is_required():
        return "required"
    if field.default_factory is not None:
        return _value(field.default_factory())  # type: ignore[call-arg]
    return _value(field.default) if field.default is not PydanticUndefined else "required"


def rows(model: type[BaseModel], prefix: str = "") -> Iterator[Row]:
    """One row per key of ``model`` and, depth first, of the sections it holds."""
    for name, field in model.model_fields.items():
        key = prefix + name
        tp = Annotated[(field.annotation, *field.metadata)] if field.metadata else \
            field.annotation
        text, ranges = type_text(tp)
        inner = nested(field.annotation)
        description = field.description or (first_sentence(inner[0].__doc__, {})
                                            if inner else "")
        if not description:
            raise ValueError(f"{model.__name__}.{name} ({key}) has no description: give its "
                             "Field a description=, which the reference shows")
        yield Row(key, text, default_text(field), "; ".join(ranges), description)
        if inner is not None:
            yield from rows(inner[0], key + inner[1])


def sections() -> list[Section]:
    """Every table of the reference: the file, a custom definition, each built-in model."""
    found = [Section("Problem file", "The top level and its sections, for every model.",
                     tuple(rows(ProblemFile))),
             Section("definition (model: custom)", "The `definition` section of `model: "
                     "custom`. Its `parameters` are any names with a number or a list of "
                     "numbers each; `initial` and `final` take the states and velocities its "
                     "groupoid factors name.", tuple(rows(Definition, "definition.")))]
    for name, spec in sorted(MODELS.items()):
        found.append(Section(f"model: {name}", spec.summary + ".", tuple(
            row for section, model in (("parameters", spec.parameters),
                                       ("initial", spec.initial), ("final", spec.final))
            for row in rows(model, section + "."))))
    return found


def _cell(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ")


def markdown() -> str:
    """The reference as Markdown: one table per section."""
    out: list[str] = []
    for s in sections():
        out += [f"## {s.title}", "", s.intro, "",
                "| key | type | default | range | description |", "|---|---|---|---|---|"]
        out += [f"| `{r.key}` | {_cell(r.type)} | {_cell(r.default)} | {_cell(r.range)} | "
                f"{_cell(r.description)} |" for r in s.rows]
        out.append("")
    return "\n".join(out)
