"""A seeded mutator over every problem file (issues 15, 19 and 30): deleted keys, wrong types
and lengths, extreme numbers (1e300, +-1e308, 1e-300, huge integers, NaN-ish text), deep
nesting, aliases, duplicate keys, bad custom expressions and bad output paths. Each mutant
goes through ``ocgroupoid check`` in-process (a few through ``solve`` with a tiny N); every
run must end without a traceback, with an exit code in {0, 1, 2}, and no mutant known to be
bad may be accepted with exit 0. Values of +-1e308 in the parameters and boundary values are
bad for sure (beyond the scale double precision resolves), and N = 5000 is checked, or
refused with its time estimate, within seconds.

The cases are fixed by :data:`SEED`; a failure names the case (problem, mutation, value) so
that it can be replayed with :func:`mutants`.
"""

from __future__ import annotations

import random
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterator

import pytest
import yaml
from typer.testing import CliRunner

from ocgroupoid.cli import app

ROOT = Path(__file__).resolve().parent.parent
PROBLEMS = sorted((ROOT / "problems").glob("*.yaml"))
SEED = 19
CASES = 34  # per problem file: 9 files give ~300 `check` runs
SOLVES = 2  # per problem file, with N = 4 and at most 5 IPOPT iterations
runner = CliRunner()

# a problem whose controls u are 3 (so that u[3], u + [1, 2] and u @ u are bad for sure)
THREE_CONTROLS = {"custom_rigid_body", "reaction_wheels"}
BAD_ANYWHERE = ["pi[0]", "1/0", "10.0**1000", "(-1)**0.5", "1" * 400, "u[0:3:0]", "u[-99]",
                "u[99999999999999999999999]", "cross(u, 1)", "u[0] / (1 - 1)", "sqrt(-4)",
                "log(0) * u[0]", "__import__('os')", "u.T", "[x for x in u]", "1e999 * u[0]"]
BAD_FOR_THREE = ["u[3]", "u + [1, 2]", "u @ u"]
WRONG_TYPES: list[Any] = ["abc", True, None, [1, 2], {"a": 1}, [], "", [[1, 2], [3]]]
EXTREMES: list[Any] = [1e300, -1e300, 1e-300, 10 ** 25, -(10 ** 25), float("nan"),
                       float("inf"), -0.0, 0, -1, 2 ** 63, 1e308, -1e308]
NANISH = ["NaN", "nan", "inf", "-inf", "1e999", "1e300", "1.0e-400", "9" * 400, ".NaN",
          "infinity"]
NUMERIC_SECTIONS = {"parameters", "initial", "final", "horizon", "bounds", "objective"}
REQUIRED = {("model",), ("horizon",), ("horizon", "T"), ("horizon", "N")}


@dataclass
class Mutant:
    """One mutated problem file: its text, what was done, and whether it is bad for sure."""

    label: str
    text: str
    known_bad: bool


def leaves(node: Any, path: tuple = ()) -> Iterator[tuple[tuple, Any]]:
    """Every (path, value) of a parsed problem file, containers included."""
    yield path, node
    if isinstance(node, dict):
        for k, v in node.items():
            yield from leaves(v, (*path, k))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield from leaves(v, (*path, i))


def set_at(data: Any, path: tuple, value: Any) -> None:
    for p in path[:-1]:
        data = data[p]
    data[path[-1]] = value


def delete_at(data: Any, path: tuple) -> None:
    for p in path[:-1]:
        data = data[p]
    del data[path[-1]]


def dump(data: Any) -> str:
    return yaml.safe_dump(data, sort_keys=False, allow_unicode=True, width=1000)


def alias_bomb(levels: int) -> str:
    lines = ["b0: &b0 [lol, lol, lol, lol, lol, lol, lol, lol, lol, lol]"]
    lines += [f"b{k}: &b{k} [{', '.join([f'*b{k - 1}'] * 10)}]" for k in range(1, levels + 1)]
    return "\n".join(lines) + "\n"


class Mutator:
    """Seeded mutations of one problem file (parsed once, with N lowered for speed)."""

    def __init__(self, path: Path, seed: int) -> None:
        self.name = path.stem
        self.base = yaml.safe_load(path.read_text())
        self.base["horizon"]["N"] = min(int(self.base["horizon"]["N"]), 8)
        for level in ("continuation",):
            self.base.get("solver", {}).pop(level, None)
        self.rng = random.Random(seed)

    def fresh(self) -> Any:
        return yaml.safe_load(dump(self.base))

    def pick(self, data: Any, kind: type | tuple[type, ...] | None = None) -> tuple:
        paths = [p for p, v in leaves(data) if p and (kind is None or (
            isinstance(v, kind) and not isinstance(v, bool)))]
        return self.rng.choice(paths) if paths else ()

    def __call__(self, mild: bool = False) -> Mutant:
        """A random mutation; ``mild``: of values only (which often still solve)."""
        kinds = ["delete", "wrong_type", "length", "extreme"]
        if not mild:
            kinds += ["nanish", "deep", "alias", "self_reference", "duplicate", "special"]
            kinds += ["expression"] * 4 if "definition" in self.base else []
        return getattr(self, self.rng.choice(kinds))()

    def delete(self) -> Mutant:
        data = self.fresh()
        path = self.pick(data)
        delete_at(data, path)
        return Mutant(f"delete {path}", dump(data), path in REQUIRED)

    def wrong_type(self) -> Mutant:
        data = self.fresh()
        path, value = self.pick(data), self.rng.choice(WRONG_TYPES)
        set_at(data, path, value)
        return Mutant(f"{path} = {value!r}", dump(data), False)

    def length(self) -> Mutant:
        data = self.fresh()
        path = self.pick(data, list)
        if not path:
            return self.wrong_type()
        lst = data
        for p in path:
            lst = lst[p]
        if lst and self.rng.random() < 0.5:
            lst.pop()
            return Mutant(f"{path} shortened", dump(data), False)
        lst.append(self.rng.choice([0.0, 1.0, "x"]))
        return Mutant(f"{path} lengthened", dump(data), False)

    def extreme(self) -> Mutant:
        data = self.fresh()
        path = self.pick(data, (int, float))
        value = self.rng.choice(EXTREMES + [10 ** 400])
        set_at(data, path, value)
        # none of the extremes is a valid T, T_min, T_max or N
        return Mutant(f"{path} = {value!r:.40}", dump(data),
                      value == 10 ** 400 or path[0] == "horizon")

    def nanish(self) -> Mutant:
        data = self.fresh()
        path = self.pick(data, (int, float))
        token = self.rng.choice(NANISH)
        set_at(data, path, "@TOKEN@")
        text = dump(data).replace("'@TOKEN@'", token).replace("@TOKEN@", token)
        numeric = path[0] in NUMERIC_SECTIONS
        always = token in ("1e999", "1e300", "1.0e-400", "9" * 400)
        return Mutant(f"{path} = {token:.20}", text, numeric or always)

    def deep(self) -> Mutant:
        data = self.fresh()
        path = self.pick(data)
        depth = self.rng.choice([33, 100, 1000, 5000])
        set_at(data, path, "@DEEP@")
        text = dump(data).replace("'@DEEP@'", "@DEEP@")
        return Mutant(f"{path} nested {depth} deep",
                      text.replace("@DEEP@", "[" * depth + "1" + "]" * depth), True)

    def alias(self) -> Mutant:
        levels = self.rng.choice([3, 7, 8, 9])
        data = self.fresh()
        path = self.pick(data)
        set_at(data, path, "@ALIAS@")
        text = dump(data).replace("'@ALIAS@'", "@ALIAS@").replace("@ALIAS@", f"*b{levels}")
        # the anchors live under an unknown top-level key: bad either way, and a bomb must be
        # refused before anything walks it
        return Mutant(f"{path} = alias bomb of {levels} levels",
                      "bombs:\n" + "".join(f"  {line}\n" for line in
                                           alias_bomb(levels).splitlines()) + text, True)

    def self_reference(self) -> Mutant:
        data = self.fresh()
        path = self.pick(data)
        set_at(data, path, "@SELF@")
        text = dump(data).replace("'@SELF@'", "@SELF@").replace("@SELF@", "&s [1, *s]")
        return Mutant(f"{path} refers to itself", text, True)

    def duplicate(self) -> Mutant:
        lines = dump(self.fresh()).splitlines()

        def indent(s: str) -> int:
            return len(s) - len(s.lstrip(" "))

        simple = [i for i, s in enumerate(lines) if ": " in s and not s.lstrip().startswith("-")
                  and not s.rstrip().endswith(":")
                  and (i + 1 == len(lines) or indent(lines[i + 1]) <= indent(s))]
        i = self.rng.choice(simple)
        return Mutant(f"duplicate line {lines[i].strip()!r:.40}",
                      "\n".join(lines[: i + 1] + lines[i:]) + "\n", True)

    def special(self) -> Mutant:
        data = self.fresh()
        key, value = self.rng.choice([
            (("solver", "multistart"), "yes"), (("solver", "multistart"), 10_000_000),
            (("horizon", "N"), 10_000_000), (("horizon", "N"), 10 ** 20),
            (("horizon", "T"), 1e300), (("horizon", "T"), 1e-300),
            (("solver", "ipopt", "linear_solver"), "ma57"),
            (("solver", "continuation"), [10 ** 9]),
            (("solver", "continuation"), list(range(2, 12))),
            (("initial", "R"), {"quaternion": [1e300, 1e300, 1e300, 1e300]}),
            (("initial", "R"), {"quaternion": [1e308, 0.0, 0.0, 0.0]}),
            (("final", "R"), {"rotvec": [1e200, 0.0, 0.0]})])
        node = data
        for p in key[:-1]:
            node = node.setdefault(p, {})
        node[key[-1]] = value
        return Mutant(f"{key} = {value!r:.40}", dump(data), True)

    def expression(self) -> Mutant:
        data = self.fresh()
        d = data["definition"]
        keys = [(k,) for k in ("cost", "lagrangian", "terminal_cost", "input_matrix") if k in d]
        keys += [(k, n) for k in ("constraints", "path") for n in d.get(k, {})]
        keys += [("controls", n) for n in d["controls"]] if isinstance(d.get("controls"),
                                                                     dict) else []
        where = self.rng.choice(keys)
        pool = BAD_ANYWHERE + (BAD_FOR_THREE if self.name in THREE_CONTROLS else [])
        text = self.rng.choice(pool)
        set_at(d, where, text)
        return Mutant(f"definition.{'.'.join(where)} = {text:.40}", dump(data), True)


def mutants(path: Path, count: int, seed: int = SEED, mild: bool = False) -> list[Mutant]:
    """The mutants of one problem file (replay a failing case with this)."""
    m = Mutator(path, seed * 1000 + PROBLEMS.index(path))
    return [m(mild) for _ in range(count)]


def outcome(tmp_path: Path, mutant: Mutant, *args: str, command: str = "check",
            limit: float = 10.0) -> tuple[int, str, float]:
    f = tmp_path / "mutant.yaml"
    f.write_text(mutant.text)
    t0 = time.perf_counter()
    r = runner.invoke(app, [command, str(f), *args])
    seconds = time.perf_counter() - t0
    problems = []
    if "Traceback" in r.output or (r.exception is not None and
                                   not isinstance(r.exception, SystemExit)):
        problems.append(f"traceback ({r.exception!r:.200})")
    if r.exit_code not in (0, 1, 2):
        problems.append(f"exit code {r.exit_code}")
    if mutant.known_bad and r.exit_code == 0:
        problems.append("a known-bad input was accepted")
    if seconds > limit:
        problems.append(f"took {seconds:.1f} s")
    tail = " ".join(r.output.split())[-300:]
    return r.exit_code, "; ".join(problems) + (f" :: {tail}" if problems else ""), seconds


@pytest.mark.parametrize("problem", PROBLEMS, ids=lambda p: p.stem)
def test_mutated_problem_files_never_crash(problem: Path, tmp_path) -> None:
    failures, codes = [], []
    for i, mutant in enumerate(mutants(problem, CASES)):
        code, trouble, _ = outcome(tmp_path, mutant)
        codes.append(code)
        if trouble:
            failures.append(f"case {i} ({mutant.label}): {trouble}")
    assert not failures, "\n".join(failures)
    assert 2 in codes  # the mutator does reach the validation


BAD_OUTPUTS = ["", ".", "{tmp}", "{tmp}/regular/sol.json", "/proc/sol.json"]


@pytest.mark.parametrize("problem", PROBLEMS, ids=lambda p: p.stem)
def test_mutated_problem_files_solve_or_fail_cleanly(problem: Path, tmp_path) -> None:
    """The unmutated file with a bad output path (refused before the solve), then the file
    and mutants of its values solved with N = 4 and at most 5 iterations into a good one."""
    (tmp_path / "regular").write_text("a file, not a folder")
    rng = random.Random(SEED + PROBLEMS.index(problem))
    unmutated = Mutant("unmutated", dump(Mutator(problem, 0).base), False)
    runs = [(unmutated, rng.choice(BAD_OUTPUTS).format(tmp=tmp_path), True)]
    runs += [(m, str(tmp_path / "sol.json"), False)
             for m in [unmutated, *mutants(problem, SOLVES, seed=SEED + 1, mild=True)]]
    failures = []
    for i, (mutant, out, bad_out) in enumerate(runs):
        args = ["--set", "horizon.N=4", "--set", "solver.ipopt.max_iter=5", "--set",
                "solver.multistart=false", "--out", out, "-q"]
        code, trouble, _ = outcome(tmp_path, mutant, *args, command="solve")
        if bad_out and code != 2:
            trouble += f" --out {out!r} was not refused (exit {code})"
        if trouble:
            failures.append(f"case {i} ({mutant.label}, --out {out!r}): {trouble}")
    assert not failures, "\n".join(failures)


def scale_mutants(path: Path, count: int, seed: int = SEED) -> list[Mutant]:
    """``count`` numbers of the parameters and boundary values of one problem file set to
    +-1e308 (seeded): every one is beyond the scale the NLP resolves."""
    m = Mutator(path, seed * 1000 + PROBLEMS.index(path))
    paths = [p for p, v in leaves(m.base) if p and p[0] in ("parameters", "initial", "final")
             and isinstance(v, (int, float)) and not isinstance(v, bool)]
    out = []
    for p in m.rng.sample(paths, min(count, len(paths))):
        data = m.fresh()
        value = m.rng.choice([1e308, -1e308])
        set_at(data, p, value)
        out.append(Mutant(f"{p} = {value!r}", dump(data), True))
    return out


@pytest.mark.parametrize("problem", PROBLEMS, ids=lambda p: p.stem)
def test_values_of_1e308_are_refused_without_a_traceback(problem: Path, tmp_path) -> None:
    failures, codes = [], []
    for mutant in scale_mutants(problem, 6):
        code, trouble, _ = outcome(tmp_path, mutant)
        codes.append(code)
        if trouble or code != 2:
            failures.append(f"{mutant.label}: exit {code} {trouble}")
    assert not failures, "\n".join(failures)
    assert codes


LARGE_N = ["plate_ball.yaml", "reaction_wheels.yaml", "heavy_top_rotors.yaml"]


@pytest.mark.parametrize("name", LARGE_N)
def test_N_5000_is_checked_or_refused_within_its_estimate(name: str, tmp_path) -> None:
    """`check` at N = 5000 finishes in seconds; a `solve` whose estimate exceeds
    solver.max_seconds is refused at once, with the estimate."""
    problem = ROOT / "problems" / name
    mutant = Mutant("N = 5000", dump({**Mutator(problem, 0).base,
                                      "horizon": {**Mutator(problem, 0).base["horizon"],
                                                  "N": 5000}}), False)
    # the budget this test states for N = 5000 (order4, the files' default scheme, builds
    # three times order2's variables), not the 10 s of a fuzzed file at its own N
    code, trouble, seconds = outcome(tmp_path, mutant, limit=30.0)
    assert code == 0 and not trouble and seconds < 30, (code, trouble, seconds)
    (tmp_path / "mutant.yaml").write_text(mutant.text)
    t0 = time.perf_counter()
    r = runner.invoke(app, ["solve", str(tmp_path / "mutant.yaml"), "--set",
                            "solver.max_seconds=5", "-q"])
    text = " ".join(r.output.split())
    assert r.exit_code == 2 and time.perf_counter() - t0 < 10, text
    assert "horizon.N = 5000: a solve takes about" in text and "more than solver.max_seconds = 5" \
        in text and "Traceback" not in r.output
