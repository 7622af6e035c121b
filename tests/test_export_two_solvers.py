"""Exported solvers of different problems in one C program (issue 25): exported with the
prefixes ``so3_``, ``top_`` (both IPOPT) and ``ball_`` (fatrop, whose export carries its
driver), their libraries link side by side (no name of one is a name of another) and, called
in turn (A, B, C, A, B, C, each with a warm start), they give bit for bit what each gives
alone, and what Python gives.

One export of each (N = 16), each library built once, one combined program built once.
"""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest

from ocgroupoid import files
from ocgroupoid.errors import ConfigError
from ocgroupoid.export.codegen import BACKEND_LIBS, casadi_dir, export_c, make
from ocgroupoid.systems.rigid_body import rigid_body

from .cbuild import CFLAGS

ROOT = Path(__file__).resolve().parent.parent
N_TEST = 16
#: prefix -> problem file (with its own backend)
EXPORTS = {"so3_": "so3_rest_to_rest", "top_": "heavy_top_rotors", "ball_": "plate_ball"}
BACKENDS = {"so3_": "ipopt", "top_": "ipopt", "ball_": "fatrop"}

pytestmark = pytest.mark.skipif(shutil.which("cc") is None or shutil.which("make") is None,
                                reason="no C compiler (cc) or make on PATH")

# SOLVES(so3_, SO3_) defines solve_so3_(): a cold solve of the exported instance, then a
# primal-dual warm start at a 1 % longer horizon, each printed bit for bit (%a).
PROGRAM = r"""
#include <stdio.h>
#include <string.h>

#include "so3_model.h"
#include "so3_solver.h"
#include "top_model.h"
#include "top_solver.h"
#include "ball_model.h"
#include "ball_solver.h"

static void print_output(const char *name, const char *what, const double *v, size_t n) {
  size_t i;
  printf("%s %s", name, what);
  for (i = 0; i < n; ++i) printf(" %a", v[i]);
  printf("\n");
}

#define SOLVES(pre, PRE)                                                                 \
  static int solve_##pre(void) {                                                         \
    double p[PRE##NP];                                                                   \
    size_t rows, cols;                                                                   \
    const double *v;                                                                     \
    int code, round;                                                                     \
    pre##result *r = pre##result_new();                                                  \
    if (!r || pre##pack(pre##default_values, PRE##NV, p, PRE##NP, NULL) != PRE##OK)      \
      return 1;                                                                          \
    for (round = 0; round < 2; ++round) {                                                \
      const char *what = round ? "warm" : "cold";                                        \
      code = round ? pre##solve_warm(p, PRE##NP, r, r) : pre##solve(p, PRE##NP, NULL, 0, r); \
      if (code < 0) return 1;                                                            \
      printf("%s %s %d %s %d %a\n", #pre, what, code, pre##status_name(r),               \
             pre##iterations(r), pre##cost(r));                                          \
      v = pre##output(r, PRE##X, &rows, &cols);                                          \
      print_output(#pre, "x", v, rows * cols);                                           \
      v = pre##output(r, PRE##STATES, &rows, &cols);                                     \
      print_output(#pre, "states", v, rows * cols);                                      \
      v = pre##output(r, PRE##CONTROLS, &rows, &cols);                                   \
      print_output(#pre, "controls", v, rows * cols);                                    \
      p[PRE##P_T] *= 1.01;                                                               \
    }                                                                                    \
    pre##result_free(r);                                                                 \
    return 0;                                                                            \
  }

SOLVES(so3_, SO3_)
SOLVES(top_, TOP_)
SOLVES(ball_, BALL_)

/* so3, top or ball: that one alone; all: so3, top, ball, so3, top, ball */
int main(int argc, char **argv) {
  const char *which = argc > 1 ? argv[1] : "all";
  int all = strcmp(which, "all") == 0, k;
  for (k = 0; k < (all ? 2 : 1); ++k) {
    if ((all || strcmp(which, "so3") == 0) && solve_so3_()) return 2;
    if ((all || strcmp(which, "top") == 0) && solve_top_()) return 2;
    if ((all || strcmp(which, "ball") == 0) && solve_ball_()) return 2;
  }
  return 0;
}
"""


@pytest.fixture(scope="module")
def program(tmp_path_factory) -> tuple[Path, dict]:
    """Both problems exported with their prefixes, each libocg.a built, the program linked
    with both; and the Python solution of each exported instance."""
    root = tmp_path_factory.mktemp("two")
    python, libs = {}, []
    for prefix, name in EXPORTS.items():
        cfg = files.load(ROOT / "problems" / f"{name}.yaml", [])
        d, f = cfg.file.discretization, cfg.file.solver
        exp = export_c(files.build(cfg), root / name, N_TEST, d.retraction, d.rule, f.ipopt,
                       scheme=d.scheme, backend=f.backend, prefix=prefix)
        libs.append(make(exp.folder, CFLAGS, target="libocg.a"))
        python[prefix] = exp.solver.solve(multistart=False)
        assert exp.solver.transcription.backend == BACKENDS[prefix]
    lib = casadi_dir()
    source, exe = root / "two.c", root / "two"
    source.write_text(PROGRAM)
    cmd = ["cc", *CFLAGS.split(), *[f"-I{p.parent}" for p in libs],
           f"-I{lib / 'include'}", "-o", str(exe), str(source), *map(str, libs),
           f"-L{lib}", f"-Wl,-rpath,{lib}", *BACKEND_LIBS["fatrop"].split(), "-lm"]
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    return exe, python


def run(exe: Path, which: str) -> list[str]:
    r = subprocess.run([str(exe), which], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stdout + r.stderr
    return r.stdout.splitlines()


def test_solvers_called_in_turn_give_what_they_give_alone(program) -> None:
    """so3, top, ball, so3, top, ball (each a cold solve and a warm start) print what each
    prints alone, bit for bit (iterations, status, cost, NLP point, states, controls)."""
    exe, _ = program
    alone = [run(exe, prefix[:-1]) for prefix in EXPORTS]
    n = len(alone[0])
    assert n == 8 and all(len(lines) == n for lines in alone)
    every = run(exe, "all")
    assert [every[k * n:(k + 1) * n] for k in range(6)] == alone + alone


def test_each_solver_in_the_combined_program_is_pythons(program) -> None:
    """The cold solve of each export gives Python's status, iterations and cost."""
    exe, python = program
    for prefix in EXPORTS:
        code, status, iterations, cost = run(exe, prefix[:-1])[0].split()[2:]
        py = python[prefix]
        assert (status, int(iterations)) == (py.status, py.iterations)
        assert code == ("0" if py.success else "1")
        assert abs(float.fromhex(cost) - py.cost) <= 1e-8 * max(1.0, abs(py.cost))


def test_no_symbol_of_one_export_is_a_symbol_of_the_other(program) -> None:
    """Every name a library defines for the linker starts with its prefix."""
    if shutil.which("nm") is None:
        pytest.skip("nm is not installed")
    exe, _ = program
    for prefix, name in EXPORTS.items():
        r = subprocess.run(["nm", "-g", "--defined-only", str(exe.parent / name / "libocg.a")],
                           capture_output=True, text=True, check=True)
        symbols = [ln.split()[-1] for ln in r.stdout.splitlines() if len(ln.split()) == 3]
        assert symbols and [s for s in symbols if not s.startswith(prefix)] == []


@pytest.mark.parametrize("prefix", ["", "so3", "So3_", "3d_", "so-3_", "_so3_"])
def test_a_prefix_must_start_c_names(prefix: str, tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="a prefix of C names"):
        export_c(rigid_body(), tmp_path / "c", N=4, prefix=prefix)
