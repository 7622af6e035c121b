"""The YAML text of a problem file: safe loading, the line of every key, ``--set`` overrides.

Only ``yaml.safe_load`` is used; nothing in a file is executed. :class:`Locator` names where
a key came from (``file:line`` or ``--set``) for every message.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml

from ..errors import ConfigError


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
            out[(*prefix, i)] = v.start_mark.line + 1
            out.update(_lines(v, (*prefix, i)))
    return out


def read_yaml(path: str | Path) -> tuple[dict[str, Any], dict[tuple, int]]:
    """Safe-load a problem file; return the data and the line of every key."""
    path = Path(path)
    try:
        raw = path.read_bytes()
    except OSError as err:
        raise ConfigError(f"{path}: cannot read ({err.strerror}); check the path") from None
    if b"\x00" in raw:
        raise ConfigError(f"{path}: this is a binary file, not YAML; give a .yaml problem file")
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        raise ConfigError(f"{path}: not UTF-8 text; give a .yaml problem file") from None
    try:
        data = yaml.safe_load(text)
        lines = _lines(yaml.compose(text))
    except yaml.YAMLError as err:
        mark = getattr(err, "problem_mark", None)
        where = f":{mark.line + 1}:{mark.column + 1}" if mark else ""
        problem = getattr(err, "problem", None) or str(err)
        raise ConfigError(f"{path}{where}: invalid YAML ({problem}); check indentation, "
                          "colons and brackets") from None
    if data is None:
        raise ConfigError(f"{path}: the file is empty; a problem file needs at least the keys "
                          "model and horizon (see problems/ for examples)")
    if not isinstance(data, dict):
        raise ConfigError(f"{path}: the top level must be a mapping of keys (model, horizon, "
                          f"...), got a {type(data).__name__}")
    return data, lines


def apply_override(data: dict[str, Any], assignment: str) -> tuple[str, ...]:
    """Apply ``key.path=value`` (value parsed as YAML) to nested dicts; return the path."""
    if "=" not in assignment:
        raise ConfigError(f"--set {assignment!r}: expected KEY=VALUE, e.g. horizon.N=128")
    key, _, text = assignment.partition("=")
    path = tuple(p for p in key.strip().split(".") if p)
    if not path:
        raise ConfigError(f"--set {assignment!r}: empty key; write e.g. horizon.N=128")
    try:
        value = yaml.safe_load(text) if text.strip() else None
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
