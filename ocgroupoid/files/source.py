"""The YAML text of a problem file: safe loading, the line of every key, ``--set`` overrides.

Nothing in a file is executed: the loader is PyYAML's safe one, made stricter where YAML's
defaults hide mistakes. A key written twice in one mapping is an error (YAML keeps the last
silently), and so is an integer too large for a float (checked before it is converted) and a
float literal that underflows to 0. A number is read as YAML 1.2 and everybody writes it:
``1e-6``, ``1E6`` and ``.5`` are floats (YAML 1.1 reads the first two as text); its other
surprises (``yes``, ``on``) stay booleans, refused where a number is expected. A file is read
only within :data:`LIMITS`: its size, the nesting of its lists and mappings, and the number
of values once every alias (``*name``) is expanded — a self-referencing alias or an alias
bomb is refused before anything walks the expanded document. :class:`Locator` names where a
key came from (``file:line`` or ``--set``) for every message.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path
from typing import Any

import yaml

from ..errors import ConfigError
from ..model.ranges import FILE_BYTES

#: what a problem file may be: bytes, nesting depth, values after expanding aliases
LIMITS = {"bytes": FILE_BYTES, "depth": 32, "values": 100_000}
# a number YAML 1.1 reads as text (an exponent without a dot or without a sign): read as a float
_EXPONENT_NUMBER = re.compile(r"[-+]?(?:\d[\d_]*\.?[\d_]*|\.\d[\d_]*)[eE][-+]?\d+\Z")
_MANTISSA = re.compile(r"[-+]?[0.]*(?:[eE].*)?")  # a float literal whose digits are all 0
_INT_CHARS = 320  # longer integers are beyond the range of a float (309 digits)


class Refusal(Exception):
    """A YAML text the loader refuses, with its 1-based line and a message with the fix."""

    def __init__(self, line: int, message: str) -> None:
        super().__init__(message)
        self.line, self.message = line, message


def _line(node: yaml.Node) -> int:
    return node.start_mark.line + 1


class StrictLoader(yaml.SafeLoader):
    """``yaml.SafeLoader`` refusing duplicate keys and numbers beyond a float's range, and
    reading ``1e-6`` as the number it is."""

    def construct_mapping(self, node: yaml.MappingNode, deep: bool = False) -> dict:
        seen: dict[Any, int] = {}
        for key_node, _ in node.value:
            if key_node.tag == "tag:yaml.org,2002:merge":
                continue  # `<<: *base` then overriding keys is YAML's own idiom
            key = self.construct_object(key_node, deep=True)
            try:
                first = seen.get(key)
            except TypeError:
                continue  # unhashable: SafeLoader names it below
            if first is not None:
                raise Refusal(_line(key_node), f"the key {key!r} appears twice in one mapping "
                              f"(lines {first} and {_line(key_node)}); keep one of them")
            seen[key] = _line(key_node)
        return super().construct_mapping(node, deep=deep)

    def construct_yaml_int(self, node: yaml.ScalarNode) -> int:
        # checked before any conversion: Python refuses to read integers of > 4300 digits,
        # and float() of one beyond 1.8e+308 raises; counts (N) have their own limits
        if len(node.value) > _INT_CHARS or abs(value := super().construct_yaml_int(node)) > \
                sys.float_info.max:
            raise Refusal(_line(node), f"the integer {node.value[:20]}"
                          f"{'...' if len(node.value) > 20 else ''} ({len(node.value)} "
                          "characters) is too large for a float (beyond 1.8e+308); write a "
                          "smaller number")
        return value

    def construct_yaml_float(self, node: yaml.ScalarNode) -> float:
        value = super().construct_yaml_float(node)
        text = node.value.lower()
        if value in (float("inf"), float("-inf")) and "inf" not in text:
            raise Refusal(_line(node), f"{node.value} is too large for a float (beyond "
                          "1.8e+308); write a smaller number")
        if abs(value) < 2.2250738585072014e-308 and not _MANTISSA.fullmatch(text):
            raise Refusal(_line(node), f"{node.value} is too small for a float (below "
                          "2.2e-308, it would be read as 0 or lose digits); write 0 or a "
                          "larger number")
        return value


StrictLoader.add_implicit_resolver("tag:yaml.org,2002:float", _EXPONENT_NUMBER,
                                   list("-+0123456789."))
StrictLoader.add_constructor("tag:yaml.org,2002:int", StrictLoader.construct_yaml_int)
StrictLoader.add_constructor("tag:yaml.org,2002:float", StrictLoader.construct_yaml_float)


def _check_depth(text: str) -> None:
    """Refuse lists and mappings nested deeper than the limit, from the event stream (no
    recursion: PyYAML's composer would recurse once per level)."""
    depth = 0
    for event in yaml.parse(text, Loader=yaml.SafeLoader):
        if isinstance(event, yaml.CollectionStartEvent):
            depth += 1
            if depth > LIMITS["depth"]:
                assert event.start_mark is not None  # the parser marks every event
                raise Refusal(event.start_mark.line + 1, f"lists and mappings nested more than "
                              f"{LIMITS['depth']} deep; a problem file needs a few levels")
        elif isinstance(event, yaml.CollectionEndEvent):
            depth -= 1


def _children(node: yaml.Node) -> list[yaml.Node]:
    if isinstance(node, yaml.MappingNode):
        return [n for pair in node.value for n in pair]
    if isinstance(node, yaml.SequenceNode):
        return list(node.value)
    return []


def _check_expansion(root: yaml.Node) -> None:
    """Refuse a self-referencing alias, and documents whose aliases expand beyond the limits
    of values and depth; sizes are counted once per distinct node (an alias bomb costs
    microseconds here), depth-first without recursion."""
    size: dict[int, int] = {}
    height: dict[int, int] = {}
    open_nodes: set[int] = set()
    stack: list[tuple[yaml.Node, bool]] = [(root, False)]
    while stack:
        node, finished = stack.pop()
        key = id(node)
        if finished:
            children = _children(node)
            size[key] = 1 + sum(size[id(c)] for c in children)
            height[key] = 1 + max((height[id(c)] for c in children), default=0)
            open_nodes.discard(key)
            if size[key] > LIMITS["values"] or height[key] > LIMITS["depth"]:
                raise Refusal(_line(node), f"the aliases (*name) here expand to more than "
                              f"{LIMITS['values']} values or {LIMITS['depth']} levels; write "
                              "the values out")
            continue
        if key in size:
            continue
        if key in open_nodes:
            raise Refusal(_line(node), "an alias (*name) refers to a node that contains it; "
                          "a problem file cannot hold a self-referencing value")
        open_nodes.add(key)
        stack.append((node, True))
        stack.extend((c, False) for c in _children(node))


def parse_yaml(text: str) -> tuple[Any, yaml.Node | None]:
    """The data of a YAML text and its composed node (None when empty), within
    :data:`LIMITS`; raises :class:`Refusal` or ``yaml.YAMLError``."""
    if len(text.encode()) > LIMITS["bytes"]:
        raise Refusal(1, f"more than {LIMITS['bytes']} bytes; a problem file is a few "
                      "kilobytes of YAML")
    _check_depth(text)
    loader = StrictLoader(text)
    try:
        node = loader.get_single_node()
        if node is None:
            return None, None
        _check_expansion(node)
        return loader.construct_document(node), node
    finally:
        loader.dispose()


def _lines(node: yaml.Node | None, prefix: tuple = ()) -> dict[tuple, int]:
    """Map every key path of a composed YAML document to its 1-based line."""
    out: dict[tuple, int] = {}
    if isinstance(node, yaml.MappingNode):
        for k, v in node.value:
            path = (*prefix, k.value)
            out[path] = k.start_mark.line + 1
            out.update(_lines(v, path))
    elif isinstance(node, yaml.SequenceNode):
        for i, v in enumerate(node.value):
            out[prefix + (i,)] = v.start_mark.line + 1
            out.update(_lines(v, prefix + (i,)))
    return out


def read_yaml(path: str | Path) -> tuple[dict[str, Any], dict[tuple, int]]:
    """Safe-load a problem file; return the data and the line of every key."""
    path = Path(path)
    if path.is_dir():
        raise ConfigError(f"{path}: is a folder; give a .yaml problem file")
    try:
        with path.open("rb") as fh:
            raw = fh.read(LIMITS["bytes"] + 1)
    except OSError as err:
        raise ConfigError(f"{path}: cannot read ({err.strerror}); check the path") from None
    if b"\x00" in raw:
        raise ConfigError(f"{path}: this is a binary file, not YAML; give a .yaml problem file")
    if len(raw) > LIMITS["bytes"]:
        raise ConfigError(f"{path}: more than {LIMITS['bytes']} bytes; a problem file is a few "
                          "kilobytes of YAML")
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        raise ConfigError(f"{path}: not UTF-8 text; give a .yaml problem file") from None
    try:
        data, node = parse_yaml(text)
    except Refusal as err:
        raise ConfigError(f"{path}:{err.line}: {err.message}") from None
    except yaml.YAMLError as err:
        mark = getattr(err, "problem_mark", None)
        where = f":{mark.line + 1}:{mark.column + 1}" if mark else ""
        problem = getattr(err, "problem", None) or str(err)
        quote = "; a value with brackets inside a list is quoted: ['Omega[0]']" \
            if "but found '['" in problem or "but got '['" in problem else ""
        raise ConfigError(f"{path}{where}: invalid YAML ({problem}); check indentation, "
                          f"colons and brackets{quote}") from None
    if data is None:
        raise ConfigError(f"{path}: the file is empty; a problem file needs at least the keys "
                          "model and horizon (see problems/ for examples)")
    if not isinstance(data, dict):
        raise ConfigError(f"{path}: the top level must be a mapping of keys (model, horizon, "
                          f"...), got a {type(data).__name__}")
    return data, _lines(node)


def apply_override(data: dict[str, Any], assignment: str) -> tuple[str, ...]:
    """Apply ``key.path=value`` (value parsed as YAML) to nested dicts; return the path."""
    if "=" not in assignment:
        raise ConfigError(f"--set {assignment!r}: expected KEY=VALUE, e.g. horizon.N=128")
    key, _, text = assignment.partition("=")
    path = tuple(p for p in key.strip().split(".") if p)
    if not path:
        raise ConfigError(f"--set {assignment!r}: empty key; write e.g. horizon.N=128")
    try:
        value = parse_yaml(text)[0] if text.strip() else None
    except Refusal as err:
        raise ConfigError(f"--set {key}: {err.message}") from None
    except yaml.YAMLError as err:
        raise ConfigError(f"--set {key}: the value {text!r} is not valid YAML "
                          f"({getattr(err, 'problem', err)}); quote it or fix the brackets"
                          ) from None
    node = data
    for part in path[:-1]:
        if not isinstance(node.get(part), dict):
            node[part] = {}
        node = node[part]
    node[path[-1]] = value
    return path


class Locator:
    """``file:line`` of a key path, or a note that the value came from --set."""

    def __init__(self, path: str | Path | None, lines: dict[tuple, int],
                 overridden: set[tuple]) -> None:
        self.file = str(path) if path is not None else "<problem>"
        self.lines, self.overridden = lines, overridden

    def __call__(self, *key: Any) -> str:
        if any(key[: len(o)] == o or o[: len(key)] == key for o in self.overridden):
            return f"{self.file} (--set {'.'.join(map(str, key))})"
        for n in range(len(key), 0, -1):
            line = self.lines.get(tuple(key[:n]))
            if line:
                return f"{self.file}:{line}"
        return self.file
