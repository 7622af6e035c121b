"""Compiled evaluation (``solver.jit``): the NLP's Functions as machine code.

IPOPT calls five Functions per iteration (f, g, the gradient of f, the Jacobian of g, the
Hessian of the Lagrangian; :func:`~ocgroupoid.nlp.assembly.assemble`). By default CasADi's
virtual machine evaluates them; with ``jit`` they are written as C by CasADi's code
generator, compiled once by the system C compiler into a shared library, and loaded with
``casadi.external``. The library is cached per structure: its file name is a hash of the C
source, so a problem built again with the same N, scheme and boundary structure (another
process, a sweep worker, a re-run) loads it without compiling. Values (parameters p,
boundary values, T) are inputs and never enter the hash.

Measured on so3 at N = 256 (order2): evaluations 11.4 ms -> 1.2 ms per solve, a solve
26 ms -> 15 ms, against 0.8 s to generate and compile (``scripts/bench_backends.py`` states
the break-even in solves for every problem file). :func:`library` compiles any Functions the
same way: the replay's RK4 substep (:mod:`~ocgroupoid.verify.replay`) is one.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import tempfile
from collections.abc import Sequence
from pathlib import Path

import casadi as ca

from ..errors import ConfigError

#: the Functions IPOPT evaluates, by the names nlpsol looks up in its cache
NLP_FUNCTIONS = ("nlp_f", "nlp_g", "nlp_grad_f", "nlp_jac_g", "nlp_hess_l")
CFLAGS = ("-O1", "-shared", "-fPIC")  # -O1: most of -O2's speed at a fraction of its time


def cache_dir() -> Path:
    """Where compiled libraries live: ``$OCGROUPOID_JIT_CACHE``, else
    ``$XDG_CACHE_HOME/ocgroupoid/jit`` (``~/.cache/ocgroupoid/jit``)."""
    own = os.environ.get("OCGROUPOID_JIT_CACHE")
    if own:
        return Path(own)
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "ocgroupoid" / "jit"


def compiler() -> str:
    """The C compiler (``$CC``, else cc, gcc or clang on PATH)."""
    for name in (os.environ.get("CC"), "cc", "gcc", "clang"):
        if name and shutil.which(name):
            return name
    raise ConfigError("solver.jit needs a C compiler (cc, gcc or clang on PATH, or $CC): "
                      "install one, or set solver.jit: false")


def compiled(*sets: dict[str, ca.Function]
             ) -> tuple[list[dict[str, ca.Function]], bool, Path]:
    """Each set of the Functions a backend evaluates (:data:`NLP_FUNCTIONS`) loaded from one
    compiled library (built unless cached); whether it was compiled now (False: found in
    the cache); and the library's path. Sets that call the same stage Functions (IPOPT's
    beside fatrop's: :class:`~ocgroupoid.nlp.assembly.Derivatives`) share their code:
    quadrotor_min_time, order4, N = 64 compiles in 6.6 s for both, 5.9 s for fatrop's alone
    and 11 s for the two apart. The sets after the first are in the library under numbered
    names (``s1_nlp_f``) and loaded behind a Function of their own name (nlpsol finds its
    cache by name)."""
    loaded, built, path = library([_renamed(functions[name], _symbol(i, name))
                                   for i, functions in enumerate(sets)
                                   for name in NLP_FUNCTIONS])
    n = len(NLP_FUNCTIONS)
    return [{name: _renamed(fn, name)
             for name, fn in zip(NLP_FUNCTIONS, loaded[i * n:(i + 1) * n])}
            for i in range(len(sets))], built, path


def library(functions: list[ca.Function]) -> tuple[list[ca.Function], bool, Path]:
    """``functions`` (of distinct names) as machine code: generated into one C source,
    compiled into a shared library in :func:`cache_dir` unless one of the same source and
    flags is there (its file name is their hash), and loaded; whether it was compiled now;
    and the library's path."""
    gen = ca.CodeGenerator("ocg_jit.c", {"with_header": False})
    for fn in functions:
        gen.add(fn)
    with tempfile.TemporaryDirectory(prefix="ocg-jit-") as tmp:
        gen.generate(tmp + os.sep)
        source = Path(tmp, "ocg_jit.c").read_bytes()
        digest = hashlib.sha256(source + " ".join(CFLAGS).encode()).hexdigest()[:24]
        path = cache_dir() / f"ocg_jit_{digest}.so"
        built = not path.exists()
        if built:
            build(Path(tmp, "ocg_jit.c"), path)
    return [ca.external(fn.name(), str(path)) for fn in functions], built, path


def _symbol(i: int, name: str) -> str:
    """The name of set i's Function ``name`` in the library (the first set's own)."""
    return name if i == 0 else f"s{i}_{name}"


def _renamed(fn: ca.Function, name: str) -> ca.Function:
    """``fn`` under ``name``: itself if it has it, else a Function of that name calling it."""
    if fn.name() == name:
        return fn
    args = fn.mx_in()
    return ca.Function(name, args, fn.call(args), fn.name_in(), fn.name_out())


def build(source: Path, library: Path, flags: Sequence[str] = (*CFLAGS, "-lm")) -> None:
    """Compile ``source`` into ``library`` with ``flags`` (written under a temporary name,
    then renamed: concurrent builders of the same structure never load a half-written
    file)."""
    try:
        library.parent.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise ConfigError(f"solver.jit: cannot create the cache folder {library.parent} "
                          f"({e.strerror or e}); set OCGROUPOID_JIT_CACHE to a writable "
                          "folder") from None
    partial = library.with_name(f".{library.name}.{os.getpid()}")
    cmd = [compiler(), str(source), "-o", str(partial), *flags]
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        partial.unlink(missing_ok=True)
        raise ConfigError(f"solver.jit: the C compiler failed ({' '.join(cmd[:1])}): "
                          f"{r.stderr.strip()[-400:]}; set solver.jit: false")
    os.replace(partial, library)
