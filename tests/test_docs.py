"""The documentation: every code block of the site and the README runs, the generated
references list everything, and the site builds with ``mkdocs build --strict``.

Code blocks (``docs/**/*.md`` and ``README.md``), page by page, in a temporary folder holding a
link to ``problems/``:

- ``python``: run in order, one namespace per page;
- ``bash``, ``console`` (its ``$`` lines): every ``ocgroupoid ...`` command is run, and must
  exit 0. Commands are split at ``&&``; a part that sets up an environment, installs, runs the
  test suite or builds the site (:data:`CI_RUNS`) is skipped: CI runs those itself
  (``.ci/run``). Any other command is a failure: the test cannot run it;
- ``yaml``: loaded and built as a problem file through the project's loader;
- anything else fails, unless the line before the block is a mark:
  ``<!-- no-run: reason -->`` (shown for reading, not run), ``<!-- file: NAME -->`` (a YAML
  problem file the later blocks use: validated, then written as NAME) or
  ``<!-- merge-into: PATH -->`` (a YAML fragment: validated merged into the problem file PATH).
"""

from __future__ import annotations

import importlib.util
import os
import re
import shlex
import subprocess
import sys
import types
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterator, Union, get_args, get_origin

import pytest
import yaml
from pydantic import BaseModel, Field

from docsgen import cli as cli_reference, hooks, schema as schema_reference
from ocgroupoid import files
from ocgroupoid.files.custom import Definition
from ocgroupoid.files.schema import ProblemFile
from ocgroupoid.model.values import Strict
from ocgroupoid.systems import MODELS

ROOT = Path(__file__).resolve().parent.parent
PAGES = sorted((ROOT / "docs").rglob("*.md")) + [ROOT / "README.md"]
#: the commands CI runs itself, skipped in code blocks: a virtual environment, installs, the
#: test suite and the site's build
CI_RUNS = re.compile(r"^(python3? -m venv |\. \.venv/bin/activate$|(python3? -m )?pip install |"
                     r"python3? -m pytest( |$)|mkdocs (build|serve)( |$))")
FENCE = re.compile(r"^```(\w*)[^\n]*\n(.*?)^```$", re.MULTILINE | re.DOTALL)
MARK = re.compile(r"<!-- (no-run|file|merge-into): (.+?) -->\s*$")
SOLVE_TIMEOUT = 120  # seconds a documented command may take


@dataclass(frozen=True)
class Block:
    """A fenced code block: its language, its text, its line and the mark before it."""

    lang: str
    code: str
    line: int
    mark: tuple[str, str] | None


def code_blocks(text: str) -> list[Block]:
    """The fenced code blocks of a Markdown page, in order."""
    found = []
    for m in FENCE.finditer(text):
        before = text[:m.start()].rstrip("\n").rsplit("\n", 1)[-1]
        mark = MARK.search(before)
        found.append(Block(m.group(1).lower(), m.group(2), text.count("\n", 0, m.start()) + 1,
                           (mark.group(1), mark.group(2).strip()) if mark else None))
    return found


def commands(block: Block) -> Iterator[str]:
    """The commands of a shell block: continuation lines joined, ``console`` prompts only,
    ``&&`` chains split, comments and blank lines dropped."""
    text = block.code.replace("\\\n", " ")
    for line in text.splitlines():
        if block.lang == "console":
            if not line.startswith("$ "):
                continue
            line = line[2:]
        for part in line.split("&&"):
            part = part.strip()
            if part and not part.startswith("#"):
                yield part


def run_command(command: str, where: str, cwd: Path) -> None:
    """Run one documented command: ``ocgroupoid`` ones, or skip what CI runs itself."""
    if CI_RUNS.match(command):
        return
    argv = shlex.split(command, comments=True)
    if argv[0] != "ocgroupoid":
        pytest.fail(f"{where}: cannot run {command!r}; mark the block <!-- no-run: reason -->")
    done = subprocess.run([sys.executable, "-m", "ocgroupoid", *argv[1:]], cwd=cwd,
                          capture_output=True, text=True, timeout=SOLVE_TIMEOUT,
                          env={**os.environ, "MPLBACKEND": "Agg"})
    assert done.returncode == 0, (f"{where}: {command} exited {done.returncode}\n"
                                  f"{done.stdout[-2000:]}\n{done.stderr[-2000:]}")


def merged(base: dict[str, Any], extra: dict[str, Any]) -> dict[str, Any]:
    """``base`` with ``extra``'s keys, sections merged key by key."""
    out = dict(base)
    for k, v in extra.items():
        out[k] = merged(out[k], v) if isinstance(v, dict) and isinstance(out.get(k), dict) else v
    return out


def check_yaml(block: Block, where: str, cwd: Path) -> None:
    """Validate a YAML block as a problem file (whole, written as a file, or a fragment)."""
    data = yaml.safe_load(block.code)
    kind, arg = block.mark or ("", "")
    if kind == "merge-into":
        base = yaml.safe_load((ROOT / arg).read_text())
        files.build(files.load(data=merged(base, data)))
        return
    path = cwd / (arg if kind == "file" else "block.yaml")
    path.write_text(block.code)
    try:
        files.build(files.load(path))
    finally:
        if kind != "file":
            path.unlink()


def run_page(page: Path, cwd: Path) -> None:
    """Every code block of ``page``, in order, in ``cwd``."""
    namespace: dict[str, Any] = {"__name__": "__docs__"}
    rel = page.relative_to(ROOT)
    for block in code_blocks(page.read_text()):
        where = f"{rel}:{block.line}"
        if block.mark and block.mark[0] == "no-run":
            continue
        if block.lang == "python":
            exec(compile(block.code, where, "exec"), namespace)
        elif block.lang in ("bash", "sh", "shell", "console"):
            for command in commands(block):
                run_command(command, where, cwd)
        elif block.lang == "yaml":
            check_yaml(block, where, cwd)
        else:
            pytest.fail(f"{where}: a {block.lang or 'plain'} block the test cannot run; "
                        "mark it <!-- no-run: reason --> on the line before")


@pytest.mark.parametrize("page", PAGES, ids=[str(p.relative_to(ROOT)) for p in PAGES])
def test_code_blocks_run(page: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Every code block of the page runs (or is validated, or marked not to run)."""
    (tmp_path / "problems").symlink_to(ROOT / "problems")
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("MPLBACKEND", "Agg")
    run_page(page, tmp_path)


def test_code_block_rules() -> None:
    """The rules themselves: marks are read, chains split, CI's commands skipped, others
    refused."""
    text = "<!-- no-run: reason -->\n```c\nint x;\n```\n\n```console\n$ a && b\nout\n```\n"
    first, second = code_blocks(text)
    assert first.mark == ("no-run", "reason") and second.mark is None
    assert list(commands(second)) == ["a", "b"]
    for skipped in ("python3 -m venv .venv", ". .venv/bin/activate", 'pip install -e ".[test]"',
                    "python -m pytest -q -n 2", "mkdocs serve"):
        assert CI_RUNS.match(skipped), skipped
    with pytest.raises(pytest.fail.Exception, match="cannot run"):
        run_command("make -C so3_c", "page.md:1", ROOT)


# ------------------------------------------------------------------ the generated references


def section_models(tp: Any, path: str) -> Iterator[tuple[type[BaseModel], str]]:
    """The section models an annotation holds, with how their keys continue ``path``."""
    origin = get_origin(tp)
    if isinstance(tp, type) and issubclass(tp, BaseModel):
        yield tp, path + "."
    elif origin is list:
        yield from section_models(get_args(tp)[0], path + "[]")
    elif origin is dict:
        yield from section_models(get_args(tp)[1], path + ".<name>")
    elif origin in (Union, types.UnionType) or str(origin).endswith("Annotated"):
        for arg in get_args(tp):
            yield from section_models(arg, path)


def accepted(model: type[BaseModel], prefix: str = "") -> set[str]:
    """Every key ``model`` accepts, nested sections walked."""
    keys = set()
    for name, field in model.model_fields.items():
        keys.add(prefix + name)
        for sub, path in section_models(field.annotation, prefix + name):
            keys |= accepted(sub, path)
    return keys


def schema_keys() -> set[tuple[str, str]]:
    """(section, key) for every key a problem file accepts."""
    found = {("Problem file", k) for k in accepted(ProblemFile)}
    found |= {("definition (model: custom)", k) for k in accepted(Definition, "definition.")}
    for name, spec in MODELS.items():
        for section, model in (("parameters", spec.parameters), ("initial", spec.initial),
                               ("final", spec.final)):
            found |= {(f"model: {name}", k) for k in accepted(model, section + ".")}
    return found


def documented_rows(markdown: str) -> dict[tuple[str, str], list[str]]:
    """(section, key) -> the other cells of its row, from the generated reference."""
    rows: dict[tuple[str, str], list[str]] = {}
    section = ""
    for line in markdown.splitlines():
        if line.startswith("## "):
            section = line[3:].strip()
        m = re.match(r"^\| `([^`]+)` \|(.*)\|$", line)
        if m:
            rows[(section, m.group(1))] = [c.strip() for c in m.group(2).split(" | ")]
    return rows


def test_reference_lists_every_problem_file_key() -> None:
    """The generated problem-file reference has one row per key the schema accepts, none
    more, each with a type, a default and a description."""
    rows = documented_rows(schema_reference.markdown())
    expected = schema_keys()
    assert not expected - set(rows), f"keys missing from the reference: {expected - set(rows)}"
    assert not set(rows) - expected, f"keys the schema does not accept: {set(rows) - expected}"
    for key, (kind, default, _, description) in rows.items():
        assert kind and default and description, f"{key}: incomplete row {rows[key]}"


def test_undocumented_key_fails_the_reference() -> None:
    """A key added without a description stops the reference (and the site's build)."""
    class Section(Strict):
        documented: int = Field(1, description="a key with its description")
        undocumented: int = 2

    with pytest.raises(ValueError, match="undocumented.*no description"):
        list(schema_reference.rows(Section))


def test_cli_reference_lists_every_command_and_option() -> None:
    """Every command and every option of the command line (``--help`` apart) is in the
    generated reference."""
    markdown = cli_reference.markdown()
    for name, cmd in cli_reference.walk(cli_reference.command()):
        assert f"`{name}`" in markdown, name
        for param in cmd.get_params(cli_reference.context(cmd, name)):
            if param.name == "help":
                continue
            for opt in param.opts if param.param_type_name == "option" else []:
                assert f"`{opt}`" in markdown, f"{name} {opt}"


def test_every_marker_has_a_generator() -> None:
    """Every ``<!-- generated: NAME -->`` marker of the pages is filled."""
    for page in PAGES:
        assert hooks.MARKER.search(hooks.fill(page.read_text(), str(page))) is None, page


@pytest.mark.skipif(importlib.util.find_spec("mkdocs") is None,
                    reason="mkdocs is not installed (pip install -e '.[docs]'); CI runs "
                    "mkdocs build --strict directly")
def test_site_builds_strict(tmp_path: Path) -> None:
    """``mkdocs build --strict`` passes: no broken link, no unreadable docstring."""
    done = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir",
                           str(tmp_path / "site")], cwd=ROOT, capture_output=True, text=True,
                          env={**os.environ, "NO_MKDOCS_2_WARNING": "1"}, timeout=300)
    assert done.returncode == 0, done.stderr[-4000:]
