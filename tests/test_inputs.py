"""Input robustness (issues 15 and 19): every hostile or mistaken input is answered with exit 2
and one line naming the key, the line and the fix — never a traceback, a hang or a silently
different problem. One test per item; the fuzz test (test_fuzz.py) mixes them."""

from __future__ import annotations

import json
import time
from pathlib import Path

import casadi as ca
import numpy as np
import pytest
from typer.testing import CliRunner

from ocgroupoid import files
from ocgroupoid.cli import app
from ocgroupoid.errors import ConfigError, OcgError
from ocgroupoid.files.expressions import compile_expression
from ocgroupoid.model.values import number
from ocgroupoid.nlp.program import casadi_name
from ocgroupoid.systems.rigid_body import rigid_body

ROOT = Path(__file__).resolve().parent.parent
SO3 = (ROOT / "problems" / "so3_rest_to_rest.yaml").read_text().replace("N: 64", "N: 16")
CUSTOM = (ROOT / "problems" / "custom_rigid_body.yaml").read_text().replace("N: 64", "N: 8")
CART = (ROOT / "problems" / "cart_pole.yaml").read_text()
runner = CliRunner()


def run(tmp_path: Path, text: str, *args: str, name: str = "p.yaml", command: str = "check"
        ) -> tuple[int, str]:
    """Exit code and one-line output of ``ocgroupoid COMMAND file ARGS``, no traceback."""
    f = tmp_path / name
    f.write_text(text)
    r = runner.invoke(app, [command, str(f), *args])
    assert "Traceback" not in r.output, r.output
    assert r.exception is None or isinstance(r.exception, SystemExit), repr(r.exception)
    assert r.exit_code in (0, 1, 2)
    return r.exit_code, " ".join(r.output.split())


def refused(tmp_path: Path, text: str, *expected: str, args: tuple[str, ...] = ()) -> str:
    code, out = run(tmp_path, text, *args)
    assert code == 2, out
    for e in expected:
        assert e in out, f"{e!r} not in {out!r}"
    return out


def line_of(text: str, needle: str) -> int:
    return next(i + 1 for i, ln in enumerate(text.splitlines()) if needle in ln)


def custom_with(key: str, value: str, text: str = CUSTOM) -> str:
    out = []
    for line in text.splitlines():
        if line.strip().startswith(f"{key}:"):
            indent = line[: len(line) - len(line.lstrip())]
            line = f'{indent}{key}: "{value}"'
        out.append(line)
    return "\n".join(out) + "\n"


# -- issue 19, item 1: any file name -------------------------------------------------------


@pytest.mark.parametrize("name", ["my-slew.yaml", "2 slews.yaml", "a b.yaml"])
def test_problem_file_named_like_my_slew_checks_and_solves(tmp_path, name: str) -> None:
    assert run(tmp_path, SO3, name=name)[0] == 0
    out = tmp_path / "sol.json"
    code, text = run(tmp_path, SO3, "--out", str(out), name=name, command="solve")
    assert code == 0, text
    assert json.loads(out.read_text())["problem"] == name.removesuffix(".yaml")  # display name


def test_problem_file_named_like_my_slew_exports(tmp_path) -> None:
    code, text = run(tmp_path, SO3, "--out", str(tmp_path / "c"), name="my-slew.yaml",
                     command="export-c")
    assert code == 0, text
    generated = (tmp_path / "c" / "ocg_generated.c").read_text()
    assert "my_slew_N16" in generated  # the internal name is the one codegen uses


@pytest.mark.parametrize("name", ["my-slew", "2 slews", "a b", "", "___", "Ω", "null", "a__b",
                                  "x" * 300, "a\nX := $(shell rm -rf /)", "jac", "hess_"])
def test_casadi_name_is_a_valid_function_name(name: str) -> None:
    safe = casadi_name(name)
    x = ca.SX.sym("x")
    ca.Function(f"{safe}_N8", [x], [2 * x])  # raises if the name is not valid
    assert safe.replace("_", "").isalnum() and safe[0].isalpha() and "__" not in safe


# -- issue 19, item 4: no silently wrong input -------------------------------------------


def test_overflowing_quaternion_is_refused_with_key_and_line(tmp_path) -> None:
    text = SO3.replace("{axis_angle: {axis: [1.0, 2.0, 3.0], angle: 2.5}}",
                       "{quaternion: [1.0e+300, 1.0e+300, 1.0e+300, 1.0e+300]}")
    refused(tmp_path, text, f"p.yaml:{line_of(text, 'quaternion')}", "final.R",
            "norm overflows", "[1e+300, 1e+300, 1e+300, 1e+300]", "scale it down")


def test_huge_index_in_a_custom_model_is_out_of_range_not_wrapped(tmp_path) -> None:
    text = custom_with("cost", "0.5 * u[99999999999999999999999]**2")
    refused(tmp_path, text, f"p.yaml:{line_of(text, 'cost:')}", "definition.cost",
            "index 99999999999999999999999 is out of range for u, which has 3 components")


# -- issue 19, items 5, 6, 9: YAML ---------------------------------------------------------

def alias_bomb(levels: int) -> str:
    """The 791-byte bomb of the issue: ten aliases per level."""
    lines = ['a0: &a0 ["lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol"]']
    lines += [f"a{k}: &a{k} [{', '.join([f'*a{k - 1}'] * 10)}]" for k in range(1, levels + 1)]
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize("levels", [7, 8])
def test_alias_bomb_is_answered_within_a_second(tmp_path, levels: int) -> None:
    t0 = time.perf_counter()
    refused(tmp_path, alias_bomb(levels) + SO3, "aliases (*name)", "expand to more than")
    assert time.perf_counter() - t0 < 1.0


def test_self_referencing_yaml_is_refused(tmp_path) -> None:
    text = SO3 + "extra: &a [*a]\n"
    refused(tmp_path, text, f"p.yaml:{line_of(text, 'extra')}", "self-referencing")


@pytest.mark.parametrize("depth", [40, 5000])
def test_deep_nesting_is_refused_with_a_limit(tmp_path, depth: int) -> None:
    text = SO3 + "extra: " + "[" * depth + "]" * depth + "\n"
    refused(tmp_path, text, f"p.yaml:{line_of(text, 'extra')}", "nested more than 32 deep")


def test_duplicate_keys_are_refused(tmp_path) -> None:
    text = SO3.replace("  N: 16\n", "  N: 16\n  N: 32\n")
    refused(tmp_path, text, "the key 'N' appears twice", f"lines {line_of(text, 'N: 16')} and "
            f"{line_of(text, 'N: 32')}", "keep one of them")


@pytest.mark.parametrize("written, value", [("5e0", 5.0), ("5E0", 5.0), (".5e1", 5.0),
                                            ("50e-1", 5.0), ("5.0", 5.0), ("+5e+0", 5.0)])
def test_numbers_are_numbers_however_written(tmp_path, written, value) -> None:
    """``1e-6`` is a number, as everybody writes it (YAML 1.1 would read it as text)."""
    path = tmp_path / "p.yaml"
    path.write_text(SO3.replace("T: 5.0", f"T: {written}"))
    T = files.load(path).file.horizon.T
    assert isinstance(T, float) and T == value


@pytest.mark.parametrize("where", ["file", "--set"])
@pytest.mark.parametrize("written", ["1e-6", "1E-6", "1.0e-6", ".1e-5"])
def test_accuracy_written_as_everybody_writes_it(tmp_path, where, written) -> None:
    path = tmp_path / "p.yaml"
    text = SO3.replace("N: 16", "N: auto")
    if where == "file":
        text = text.replace("solver:\n", f"solver:\n  accuracy: {written}\n")
    path.write_text(text)
    overrides = [f"solver.accuracy={written}"] if where == "--set" else []
    assert files.load(path, overrides).file.solver.accuracy == 1e-6


@pytest.mark.parametrize("written", ["yes", "on", "true"])
def test_yaml_booleans_stay_refused_where_a_number_is_expected(tmp_path, written) -> None:
    refused(tmp_path, SO3.replace("T: 5.0", f"T: {written}"), "horizon.T")


@pytest.mark.parametrize("value, expected", [
    ("9" * 400, "too large for a float"), ("9" * 5000, "too large for a float"),
    ("1.0e-400", "too small for a float"), ("1.0e+400", "too large for a float")])
def test_numbers_beyond_a_float_are_refused_before_conversion(tmp_path, value, expected
                                                              ) -> None:
    text = SO3.replace("inertia: [1.0, 2.0, 3.0]", f"inertia: [1.0, 2.0, {value}]")
    refused(tmp_path, text, f"p.yaml:{line_of(text, 'inertia')}", expected)


def test_integer_beyond_a_float_is_refused_by_the_api() -> None:
    with pytest.raises(ConfigError, match="too large for a float"):
        number(10 ** 400, "inertia")
    with pytest.raises(ConfigError, match="too large for a float"):
        rigid_body([1.0, 2.0, 10 ** 400])


def test_huge_rotvec_names_key_and_line(tmp_path) -> None:
    text = SO3.replace("{axis_angle: {axis: [1.0, 2.0, 3.0], angle: 2.5}}",
                       "{rotvec: [1.0e+200, 0, 0]}")
    refused(tmp_path, text, f"p.yaml:{line_of(text, 'rotvec')}", "final.R",
            "rotation angle", "reduce it modulo 2 pi")


@pytest.mark.parametrize("T", ["1.0e+300", "1.0e-300", "1.0e+7", "1.0e-7"])
def test_horizon_T_outside_its_range_is_refused_with_the_range(tmp_path, T: str) -> None:
    text = SO3.replace("T: 5.0", f"T: {T}")
    refused(tmp_path, text, f"p.yaml:{line_of(text, 'T:')}", "horizon.T", "[1e-06, 1e+06]",
            "rescale the units of time")


@pytest.mark.parametrize("N", ["10000000", "100000000000000000000"])
def test_N_beyond_the_memory_estimate_is_refused_with_the_limit(tmp_path, N: str) -> None:
    text = SO3.replace("N: 16", f"N: {N}")
    out = refused(tmp_path, text, f"p.yaml:{line_of(text, 'N:')}", f"horizon.N = {N}",
                  "GB of memory", "the limit here is N <=")
    assert 1000 < int(out.split("N <= ")[1].split(";")[0]) < int(N)


def test_multistart_count_is_bounded_by_check(tmp_path) -> None:
    text = SO3 + "  multistart: 10000000\n"
    refused(tmp_path, text, f"p.yaml:{line_of(text, 'multistart')}", "solver.multistart",
            "outside 0..1000")


@pytest.mark.parametrize("value", ["'yes'", "'true'", "1.5", "[1]"])
def test_multistart_is_a_strict_bool_or_count(tmp_path, value: str) -> None:
    refused(tmp_path, SO3 + f"  multistart: {value}\n", "solver.multistart",
            "multistart is true, false or a number")


@pytest.mark.parametrize("levels, expected", [
    ("[2, 3, 4, 5, 6, 7, 8, 9, 10]", "at most 8 are allowed"),
    ("[4, 1000000000]", "must be coarser than horizon.N = 16"),
    ("[order3]", "order2")])
def test_continuation_levels_are_bounded(tmp_path, levels: str, expected: str) -> None:
    text = SO3 + f"  continuation: {levels}\n"
    refused(tmp_path, text, f"p.yaml:{line_of(text, 'continuation')}", "solver.continuation",
            expected)


def test_unavailable_linear_solver_names_the_available_ones(tmp_path) -> None:
    text = SO3.replace("ipopt: {tol: 1.0e-10}", "ipopt: {tol: 1.0e-10, linear_solver: ma57}")
    refused(tmp_path, text, f"p.yaml:{line_of(text, 'linear_solver')}",
            "solver.ipopt.linear_solver: 'ma57' is not available", "choose one of mumps")


@pytest.mark.parametrize("option, expected", [
    ("tol: -1", "solver.ipopt.tol: IPOPT refuses -1: its range is 0 < (1e-08) <= +inf"),
    ("print_level: 99", "its range is 0 <= (5) <= 12"),
    ("mu_strategy: bogus", "choose one of monotone, adaptive"),
    ("foo: 1", "IPOPT has no option 'foo'"),
    ("max_iter: many", "'many' has the wrong type"),
    ("tol: .nan", "nan is not finite"),
    ("mu_allow_fast_monotone_decrease: no", 'false is a YAML boolean (YAML reads an unquoted '
     'yes, no, true or false as one); IPOPT\'s switches take text: write "no" in quotes'),
    ("warm_start_init_point: true", 'write "yes" in quotes')])
def test_ipopt_options_are_checked_before_the_build(tmp_path, option: str, expected: str
                                                     ) -> None:
    text = SO3.replace("ipopt: {tol: 1.0e-10}", f"ipopt: {{{option}}}")
    out = refused(tmp_path, text, f"p.yaml:{line_of(text, 'ipopt:')}", expected)
    assert "casadi" not in out and "###" not in out  # one line, no IPOPT documentation dump


def test_messages_show_a_long_value_by_its_beginning(tmp_path) -> None:
    value = "[" + ", ".join(["[1, 2, 3, 4, 5, 6, 7, 8, 9, 10]"] * 1000) + "]"
    for key, old in (("retraction", "retraction: cayley"), ("Omega", "Omega: [0.0, 0.0, 0.0]")):
        text = SO3.replace(old, f"{key}: {value}", 1)
        out = refused(tmp_path, text, f"p.yaml:{line_of(text, key + ': [[')}", "...")
        assert len(out) < 300 + len(str(tmp_path)), out


# -- issue 19, item 6: custom expressions checked at parse time ----------------------------

BAD_EXPRESSIONS = {
    "u[3]": "index 3 is out of range for u, which has 3 components",
    "u[-99]": "index -99 is out of range for u",
    "u[0:3:0]": "a slice step cannot be zero",
    "pi[0]": "pi is a number and has no components",
    "1/0": "1 / 0 divides by zero",
    "10.0**1000": "10.0 ** 1000 overflows",
    "(-1)**0.5": "has no real value",
    "1" * 400: "the integer of about 400 digits is too large for a float",
    "cross(u, 1)": "cross needs two 3-vectors of one shape",
    "u + [1, 2]": "u (3x1) + [1, 2] (2x1): the shapes differ",
    "u @ u": "u (3x1) @ u (3x1): a matrix product needs",
    "sqrt(-1) * u[0]": "sqrt(-1) is undefined (NaN)",
    "u[0] / (2 - 2)": "divides by zero",
    "u[0:2]": "the cost integrand is a scalar",
}


@pytest.mark.parametrize("expression", list(BAD_EXPRESSIONS))
def test_bad_custom_expression_is_named_at_parse_time(tmp_path, expression: str) -> None:
    text = custom_with("cost", expression)
    refused(tmp_path, text, f"p.yaml:{line_of(text, 'cost:')}", "definition.cost",
            BAD_EXPRESSIONS[expression])


def test_a_sum_of_400_terms_compiles_without_recursion(tmp_path) -> None:
    poly = " + ".join(f"{k + 1}e-3 * u[{k % 3}] * u[{(k + 1) % 3}]" for k in range(400))
    assert run(tmp_path, custom_with("cost", f"0.5 * dot(u, u) + 1e-6 * ({poly})"))[0] == 0
    x = ca.SX.sym("x")
    e = compile_expression(" + ".join(["x**2"] * 2000), {"x": x}, "k")
    assert float(ca.substitute(e, x, ca.SX(2.0))) == 8000.0


def test_expressions_too_deep_for_the_parser_are_refused() -> None:
    x = ca.SX.sym("x")
    for text in (" + ".join(["x"] * 20000), "-" * 100000 + "x", "x**" * 20000 + "x"):
        with pytest.raises(ConfigError, match="too deeply"):
            compile_expression(text, {"x": x}, "k")


# -- issue 15, smaller items -------------------------------------------------------------


def test_short_parameter_vector_names_the_parameter(tmp_path) -> None:
    text = CUSTOM.replace("inertia: [1.0, 2.0, 3.0]", "inertia: [1.0, 2.0]")
    refused(tmp_path, text, "definition.lagrangian", "inertia (2x1) * Omega (3x1)",
            "the shapes differ")


def test_empty_parameter_vector_is_refused(tmp_path) -> None:
    text = CUSTOM.replace("inertia: [1.0, 2.0, 3.0]", "inertia: []")
    refused(tmp_path, text, f"p.yaml:{line_of(text, 'inertia: []')}", "parameters.inertia",
            "empty list")


def test_pi_in_boundary_values_as_in_expressions(tmp_path) -> None:
    f = tmp_path / "cart.yaml"
    f.write_text(CART.replace("theta: [3.141592653589793]", "theta: [pi]"))
    assert files.load(f).final.theta == [np.pi]
    text = SO3.replace("angle: 2.5", "angle: pi/2").replace(
        "Omega: [0.0, 0.0, 0.0]\ndiscretization", "Omega: [0, 0, -pi/8]\ndiscretization")
    f.write_text(text)
    cfg = files.load(f)
    assert cfg.final.Omega == [0.0, 0.0, -np.pi / 8]
    assert np.isclose(np.arccos((np.trace(cfg.final.R) - 1) / 2), np.pi / 2)
    assert run(tmp_path, text)[0] == 0
    refused(tmp_path, SO3.replace("angle: 2.5", "angle: pi/0"), "final.R", "divides by zero")


@pytest.mark.parametrize("actuated", ["Omega", "[Omega]", "['Omega[0]', 'Omega[1:3]']",
                                      "'Omega[0], Omega[1], Omega[2]'", "[0, 1, 2]",
                                      "['Omega[-3]', 'Omega[1]', 'Omega[2]']"])
def test_actuated_accepts_what_a_user_writes(tmp_path, actuated: str) -> None:
    f = tmp_path / "p.yaml"
    f.write_text(CUSTOM.replace("actuated: [Omega]", f"actuated: {actuated}"))
    pb = files.build(files.load(f))
    assert [n for n, _ in pb.controls] == ["u1", "u2", "u3"]


@pytest.mark.parametrize("actuated, expected", [
    ("[R]", "R is a state: its velocity is Omega"),
    ("[Omga]", "did you mean 'Omega'"),
    ("['Omega[3]']", "Omega has 3 components (0..2)"),
    ("['Omega[0], Omega[0]']", "a second time"),
    ("['Omega[0:3:0]']", "a step, if any, is not 0"),
    ("[7]", "index 7 is out of range"),
    ("['Omega[x]']", "write an integer index or a slice")])
def test_actuated_mistakes_are_named(tmp_path, actuated: str, expected: str) -> None:
    text = CUSTOM.replace("actuated: [Omega]", f"actuated: {actuated}")
    refused(tmp_path, text, f"p.yaml:{line_of(text, 'actuated')}", "definition.actuated",
            expected)


def test_brackets_in_a_flow_list_suggest_quotes(tmp_path) -> None:
    text = CUSTOM.replace("actuated: [Omega]", "actuated: [Omega[0], Omega[1]]")
    refused(tmp_path, text, "invalid YAML", "['Omega[0]']")


def test_mx_symbol_in_the_api_says_use_sx() -> None:
    pb = rigid_body([1.0, 2.0, 3.0])
    x = ca.MX.sym("x")
    for call in (lambda: pb.minimize(x), lambda: pb.subject_to(x, name="c2"),
                 lambda: pb.bound(x, -1.0, 1.0), lambda: pb.terminal_cost(x),
                 lambda: pb.bound(pb.velocity("Omega")[0], x, 1.0, name="b")):
        with pytest.raises(ConfigError, match=r"MX expression.*ca\.SX\.sym"):
            call()
    from ocgroupoid import Groupoid, LieGroupFactor, Problem
    from ocgroupoid.lie import SO3 as SO3Group
    fresh = Problem(Groupoid(LieGroupFactor(SO3Group, state="R", velocity="Omega")))
    with pytest.raises(OcgError, match="ca.SX.sym"):
        fresh.mechanics(ca.MX.sym("l"), "Omega")


def test_boundary_values_are_refused_alike_wherever_they_are_given() -> None:
    """One parser (ocgroupoid.model.boundary_values, issue 25): a problem's initial/final, the
    overrides of one instance and a simulation's initial values name a mistake alike."""
    import ocgroupoid as og
    from ocgroupoid.nlp import Discretization, Transcription

    pb = rigid_body()
    unknown = r"initial\.Omgea: unknown; states are \['R'\], velocities \['Omega'\]"
    for give in (lambda: pb.initial(Omgea=[0, 0, 0]),
                 lambda: Transcription(pb, Discretization(N=4)).pack(initial={"Omgea": [0, 0, 0]}),
                 lambda: og.simulate(pb, steps=1, initial={"Omgea": [0, 0, 0]})):
        with pytest.raises(ConfigError, match=unknown):
            give()
    G = og.Groupoid(og.Pair(1, "x", "v"))
    first = og.Problem(G, name="line", order=1)
    first.minimize(0.5 * ca.sumsqr(first.velocity("v")))
    first.report_controls(first.velocity("v"), ["v"])
    first.initial(x=[0.0])
    first.final(x=[1.0])
    first.horizon(1.0)
    velocity = r"final\.v: a first-order problem takes no velocity conditions"
    for give in (lambda: first.final(v=[0.0]),
                 lambda: Transcription(first, Discretization(N=4)).pack(final={"v": [0.0]})):
        with pytest.raises(ConfigError, match=velocity):
            give()
