"""Building an export: where IPOPT's library and headers are, and ``make``."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import casadi as ca

from ..errors import ExportError
from ..solve.parallel import cores


def casadi_dir() -> Path:
    """The folder of the casadi package: libipopt.so and include/coin-or live there."""
    return Path(ca.__file__).resolve().parent


def ipopt_paths(lib: str | Path | None, include: str | Path | None) -> tuple[Path, Path]:
    """The folders of libipopt and of IPOPT's headers: the given ones, else the casadi
    wheel's; ExportError when they do not hold them."""
    lib = Path(lib) if lib is not None else casadi_dir()
    include = Path(include) if include is not None else casadi_dir() / "include"
    if not any(lib.glob("libipopt.so*")) and not any(lib.glob("libipopt*.dylib")):
        raise ExportError(f"no libipopt in {lib}; pass ipopt_lib= (or IPOPT_LIB=... to make) "
                          "with the folder that holds libipopt.so")
    if not (include / "coin-or" / "IpStdCInterface.h").is_file():
        raise ExportError(f"no coin-or/IpStdCInterface.h under {include}; pass ipopt_include= "
                          "(or IPOPT_INCLUDE=... to make) with IPOPT's include folder")
    return lib, include


def make(folder: str | Path, cflags: str = "", target: str = "solve",
         timeout: float = 600.0) -> Path:
    """Run ``make -C folder target`` with extra ``CFLAGS``, one job per core (the generated
    files compile apart); the path of the built target (``solve``, or a program ``target``
    built from ``folder/target.c`` and libocg.a)."""
    folder = Path(folder)
    tool = shutil.which("make")
    if tool is None:
        raise ExportError("`make` was not found on PATH; install make and a C compiler "
                          "(e.g. apt-get install build-essential) or build by hand (README)")
    cmd = [tool, "-C", str(folder), f"-j{cores()}", target] + \
        ([f"CFLAGS={cflags}"] if cflags else [])
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    if r.returncode != 0:
        tail = "\n".join((r.stdout + r.stderr).strip().splitlines()[-20:])
        raise ExportError(f"building {folder / target} failed (make exit {r.returncode}):\n"
                          f"{tail}\nCheck that a C compiler is installed and that IPOPT_LIB/"
                          "IPOPT_INCLUDE in the Makefile point at libipopt and its headers.")
    return folder / target
