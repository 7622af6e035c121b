"""fatrop through its own C interface: the stage form's blocks mapped once, in time linear in N.

CasADi's fatrop ``nlpsol`` derives the stage blocks of the Jacobian and the Hessian from the
NLP's sparsity as it is built, by assigning the blocks one at a time into a sparse matrix:
its build grows as N² (so3 at N = 1024: 3.3 s, against IPOPT's 0.01 s). fatrop itself sets
up in time linear in N (19 ms for 1024 stages of so3's size). :class:`FatropOcp` drives
fatrop's C interface (``fatrop/ocp/OCPCInterface.h``, shipped with CasADi) with the stage
form's five Functions: a small C driver (``fatrop_ocp.c``, the callbacks of CasADi's
interface) scatters each nonzero of the Jacobian and the Hessian to its place in the dense
stage blocks by an index computed here (:func:`block_maps`), one per nonzero. With ``jit``
the Functions are machine code in a library of their own; without, CasADi evaluates them
as it does for its own ``nlpsol``, each through a FunctionBuffer (:class:`Buffers`: no
copy of the Functions, so the build stays linear in N). The driver is compiled once
per machine into the :func:`~ocgroupoid.nlp.jit.cache_dir`. The solve is the one CasADi's
interface runs: the same Functions, callbacks, splitting of rows and bounds, and options.
"""

from __future__ import annotations

import ctypes
import hashlib
import math
import os
import sys
import threading
import weakref
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import Any, Callable, cast

import casadi as ca
import numpy as np

from ...errors import ConfigError
from ..isolated import Stopped
from ..jit import NLP_FUNCTIONS, build, cache_dir
from ..stageform import NotStaged, StageForm
from .base import never

SOURCE = Path(__file__).with_name("fatrop_ocp.c")
#: its structs and entry points, which the exported C solver includes too
HEADER = Path(__file__).with_name("fatrop_ocp.h")
#: the guard of a solve in the caller's process, compiled with the driver
GUARD = (Path(__file__).with_name("fatrop_guard.c"), Path(__file__).with_name("fatrop_guard.h"))
#: fatrop's kinds of option (``fatrop_ocp_c_option_type``; -1 for a name it does not have)
DOUBLE, INT, BOOL, STRING = 0, 1, 2, 3
#: what a value of each kind is, for the message that rejects another
KIND_NAMES = {DOUBLE: "a number", INT: "an integer", BOOL: "true or false", STRING: "a string"}
_INT_P = ctypes.POINTER(ctypes.c_int)
_DOUBLE_P = ctypes.POINTER(ctypes.c_double)
_EVAL = ctypes.c_void_p
#: the caller's stop request, asked by a guarded solve (nonzero: stop)
_CHECK = ctypes.CFUNCTYPE(ctypes.c_int)
#: ``iteration(k, objective, infeasibility)`` of ``struct ocg_solve``: stop?
_ITERATION = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_int, ctypes.c_double, ctypes.c_double)
#: fatrop's own max_iter (ip_convergence_check.hpp), where the options set none
FATROP_MAX_ITER = 1000
#: the most inputs and outputs of an NLP Function (nlp_hess_l's, nlp_jac_g's)
MAX_IN, MAX_OUT = 4, 2
#: the arrays of one solve: its inputs, then its outputs (``x`` is the driver's ``z``)
SOLVE_ARRAYS = ("z0", "q", "lbz", "ubz", "lbg", "ubg", "z", "g", "lam_g", "lam_x", "f")


class _Problem(ctypes.Structure):
    """``struct ocg_problem`` of ``fatrop_ocp.h``."""

    _fields_ = [("K", ctypes.c_int), ("nx", _INT_P), ("nu", _INT_P), ("ng", _INT_P),
                ("col", _INT_P), ("row_ab", _INT_P), ("row_cd", _INT_P),
                ("ab_off", _INT_P), ("cd_off", _INT_P), ("rsq_off", _INT_P),
                ("nz", ctypes.c_int), ("n_rows", ctypes.c_int),
                ("nnz_a", ctypes.c_int), ("nnz_h", ctypes.c_int), ("n_ab", ctypes.c_int),
                ("n_cd", ctypes.c_int), ("n_rsq", ctypes.c_int),
                ("a_kind", _INT_P), ("a_index", _INT_P), ("h_index", _INT_P),
                ("eval", _EVAL * len(NLP_FUNCTIONS)), ("work", _EVAL * len(NLP_FUNCTIONS)),
                ("buffer_eval", _EVAL), ("buffer", _EVAL * len(NLP_FUNCTIONS)),
                ("buffer_in", (_EVAL * MAX_IN) * len(NLP_FUNCTIONS)),
                ("buffer_out", (_EVAL * MAX_OUT) * len(NLP_FUNCTIONS)),
                ("buffer_n_in", (ctypes.c_int * MAX_IN) * len(NLP_FUNCTIONS)),
                ("n_options", ctypes.c_int), ("option_names", ctypes.POINTER(ctypes.c_char_p)),
                ("option_kinds", _INT_P), ("option_values", _DOUBLE_P),
                ("option_strings", ctypes.POINTER(ctypes.c_char_p)),
                ("max_iter", ctypes.c_int)]


class _Solve(ctypes.Structure):
    """``struct ocg_solve`` of ``fatrop_ocp.h`` (its arrays by address)."""

    _fields_ = [*((name, ctypes.c_void_p) for name in SOLVE_ARRAYS),
                ("iterations", ctypes.c_int), ("return_flag", ctypes.c_int),
                ("status", ctypes.c_int), ("bad_structure", ctypes.c_int),
                ("seconds", ctypes.c_double * len(NLP_FUNCTIONS)),
                ("calls", ctypes.c_int * len(NLP_FUNCTIONS)), ("solve_seconds", ctypes.c_double),
                ("guarded", ctypes.c_int), ("nan_limit", ctypes.c_int),
                ("watch_sigint", ctypes.c_int), ("left", ctypes.c_int), ("nans", ctypes.c_int),
                ("limit", ctypes.c_double), ("every", ctypes.c_double), ("check", _CHECK),
                ("iteration", _ITERATION), ("stopped_at", ctypes.c_int)]


#: why a guarded solve was left (``ocg_solve.left``, fatrop_guard.h), as
#: :class:`~ocgroupoid.nlp.isolated.Stopped` names it
LEFT = {1: "time", 2: "nan", 3: "stop"}


@dataclass(frozen=True)
class SolveTimes:
    """Where one solve's time went, as the driver measured it: fatrop's call (``solve``,
    evaluations included) and, per NLP Function (:data:`~ocgroupoid.nlp.jit.NLP_FUNCTIONS`),
    the seconds and number of its evaluations during that call. The rest of the call is
    fatrop's own: its Riccati factorisations and solves, its line search, and the
    callbacks' copies of the stage blocks."""

    solve: float
    evaluations: dict[str, float]
    calls: dict[str, int]


@dataclass(frozen=True)
class Guard:
    """How a solve in the caller's process is left (``fatrop_guard.c``): after ``seconds``, at
    the ``nan_limit``-th non-finite evaluation, on Ctrl-C (in the main thread), or once
    ``stop()`` is true, asked from fatrop's evaluations at most every ``every`` seconds."""

    seconds: float
    stop: Callable[[], bool]
    nan_limit: int
    every: float


class Unavailable(ConfigError):
    """The driver does not compile here (no fatrop headers in CasADi's folder, say): fatrop
    runs through CasADi's nlpsol instead."""


@cache
def _fatrop() -> ctypes.CDLL:
    """fatrop's library as CasADi ships it (beside CasADi's own)."""
    folder = Path(ca.__file__).parent
    found = sorted([*folder.glob("libfatrop.*"), *folder.glob("fatrop.*")])
    if not found:
        raise ConfigError(f"fatrop's library is not in CasADi's folder ({folder}); use "
                          f"solver.backend: ipopt")
    lib = ctypes.CDLL(str(found[0]))
    lib.fatrop_ocp_c_option_type.argtypes = [ctypes.c_char_p]
    lib.fatrop_ocp_c_option_type.restype = ctypes.c_int
    return lib


def option_kinds(options: dict[str, Any]) -> dict[str, int]:
    """fatrop's kind of each option (:data:`DOUBLE`, :data:`INT`, :data:`BOOL`,
    :data:`STRING`); ConfigError naming the names fatrop does not have and the values not of
    their option's kind."""
    kinds = {name: int(_fatrop().fatrop_ocp_c_option_type(name.encode())) for name in options}
    unknown = [name for name, kind in kinds.items() if kind not in KIND_NAMES]
    if unknown:
        raise ConfigError(f"fatrop has no option {', '.join(unknown)} (fatrop's names, e.g. "
                          f"acceptable_iter, tol_acceptable, kappa_wmin)")
    wrong = [f"{name} is {KIND_NAMES[kind]}, got {options[name]!r}"
             for name, kind in kinds.items() if not _of_kind(options[name], kind)]
    if wrong:
        raise ConfigError(f"fatrop's options: {'; '.join(wrong)}")
    return kinds


def _of_kind(value: Any, kind: int) -> bool:
    """Whether ``value`` is one of fatrop's option kind ``kind``."""
    if kind == STRING:
        return isinstance(value, str)
    if kind == BOOL:
        return isinstance(value, (bool, np.bool_))
    if isinstance(value, (bool, np.bool_)):
        return False
    if kind == INT:
        return isinstance(value, (int, np.integer))
    return isinstance(value, (int, float, np.integer, np.floating))


def driver() -> ctypes.CDLL:
    """The compiled driver (``fatrop_ocp.c``), built once per machine and CasADi version
    (0.3 s); :class:`Unavailable` when it does not compile (tried once per process)."""
    lib = _driver()
    if isinstance(lib, Unavailable):
        raise lib
    return lib


@cache
def _driver() -> ctypes.CDLL | Unavailable:
    """:func:`driver`, or why it is unavailable."""
    casadi_dir = Path(ca.__file__).parent
    flags = [str(GUARD[0]), "-O2", "-shared", "-fPIC", f"-I{casadi_dir / 'include'}",
             f"-I{SOURCE.parent}", f"-L{casadi_dir}", f"-Wl,-rpath,{casadi_dir}", "-lfatrop",
             "-lblasfeo", "-lrt", "-lm"]
    source = b"".join(path.read_bytes() for path in (SOURCE, HEADER, *GUARD))
    digest = hashlib.sha256(source + " ".join(flags).encode() + ca.CasadiMeta.version().encode())
    path = cache_dir() / f"ocg_fatrop_{digest.hexdigest()[:24]}.so"
    if not path.exists():
        try:
            build(SOURCE, path, flags)
        except ConfigError as err:
            return Unavailable(f"fatrop's own interface did not compile: {err}")
    lib = ctypes.CDLL(str(path))
    lib.ocg_context_new.argtypes = [ctypes.POINTER(_Problem)]
    lib.ocg_context_new.restype = ctypes.c_void_p
    lib.ocg_context_free.argtypes = [ctypes.c_void_p]
    lib.ocg_fatrop_solve.argtypes = [ctypes.c_void_p, ctypes.POINTER(_Solve)]
    lib.ocg_fatrop_solve.restype = None
    lib.ocg_guard_available.restype = ctypes.c_int
    return lib


#: the C++ entry point of one FunctionBuffer evaluation (``casadi::_function_buffer_eval``,
#: which ``Function.buffer()`` calls), as the Itanium C++ ABI names it
BUFFER_EVAL = "_ZN6casadi21_function_buffer_evalEPv"


@cache
def buffer_eval() -> int:
    """The address of CasADi's FunctionBuffer evaluation in the library this process's
    ``casadi`` module runs on (looked up through the module's own extension: a wheel ships
    the library twice, as copies under two names, and only one is the one loaded);
    :class:`Unavailable` where it cannot be reached (another C++ ABI: Windows)."""
    module = sys.modules.get("casadi._casadi")
    try:
        lib = ctypes.CDLL(str(getattr(module, "__file__", None)),
                          mode=os.RTLD_NOLOAD | os.RTLD_LAZY)
        address = ctypes.cast(getattr(lib, BUFFER_EVAL), ctypes.c_void_p).value
    except (AttributeError, OSError) as err:
        raise Unavailable(f"CasADi's FunctionBuffer is not reachable here ({err})") from None
    if not address:
        raise Unavailable("CasADi's FunctionBuffer is not reachable here")
    return address


class Buffers:
    """A Function's FunctionBuffer (CasADi's evaluation on bound arrays, with work of its
    own) with every input and output bound to an array of its own, for the driver: it copies
    the arguments into :attr:`inputs`, evaluates, and copies the results from
    :attr:`outputs`."""

    def __init__(self, fn: ca.Function) -> None:
        #: (typed loosely: CasADi's stubs ask a byte size its binding takes from the view)
        self.buffer = cast(Any, fn.buffer()[0])
        self.inputs = [np.zeros(max(fn.nnz_in(i), 1)) for i in range(fn.n_in())]
        self.outputs = [np.zeros(max(fn.nnz_out(i), 1)) for i in range(fn.n_out())]
        for i, a in enumerate(self.inputs):
            self.buffer.set_arg(i, a.data)
        for i, a in enumerate(self.outputs):
            self.buffer.set_res(i, a.data)
        self.sizes = [fn.nnz_in(i) for i in range(fn.n_in())]

    @property
    def address(self) -> int:
        """The FunctionBuffer's address, which ``buffer_eval`` takes (from the capsule
        ``_self()`` gives, as ``Function.buffer()`` passes it)."""
        get_name, get_pointer = _capsule_api()
        capsule = self.buffer._self()
        return int(get_pointer(capsule, get_name(capsule)))


@cache
def _capsule_api() -> tuple[Any, Any]:
    """Python's ``PyCapsule_GetName`` and ``PyCapsule_GetPointer``, typed once."""
    get_name = ctypes.PYFUNCTYPE(ctypes.c_char_p, ctypes.py_object)(
        ("PyCapsule_GetName", ctypes.pythonapi))
    get_pointer = ctypes.PYFUNCTYPE(ctypes.c_void_p, ctypes.py_object, ctypes.c_char_p)(
        ("PyCapsule_GetPointer", ctypes.pythonapi))
    return get_name, get_pointer


@dataclass(frozen=True)
class BlockMaps:
    """Where each nonzero of the Jacobian and of the Hessian goes in the dense stage blocks:
    ``AB_k`` (the gap rows into x_{k+1}, negated: dF_k/d(x_k, u_k)), ``CD_k`` (stage k's
    rows) and ``RSQ_k`` (the Hessian of stage k), each column-major over ``(x_k, u_k)``;
    ``a_kind`` 0 AB, 1 CD, 2 the +1 on x_{k+1} of a gap row. Offsets per stage."""

    col: np.ndarray
    row_ab: np.ndarray
    row_cd: np.ndarray
    ab_off: np.ndarray
    cd_off: np.ndarray
    rsq_off: np.ndarray
    a_kind: np.ndarray
    a_index: np.ndarray
    h_index: np.ndarray


def block_maps(sf: StageForm, jac: ca.Sparsity, hess: ca.Sparsity) -> BlockMaps:
    """The maps of :class:`BlockMaps` for the stage form's Jacobian and Hessian patterns (CasADi's
    nonzero order); :class:`NotStaged` for a Jacobian nonzero outside every block."""
    nx, nu, ng = (np.asarray(v, dtype=np.int64) for v in (sf.nx, sf.nu, sf.ng))
    n = nx + nu
    K = sf.K
    col = np.concatenate([[0], np.cumsum(n)])
    gaps = np.append(nx[1:], 0)  # gap rows into x_{k+1} of stage k (none after K)
    row_ab = np.concatenate([[0], np.cumsum(gaps + ng)])[:K + 1]
    row_cd = row_ab + gaps
    ab_off = np.concatenate([[0], np.cumsum(gaps * n)])
    cd_off = np.concatenate([[0], np.cumsum(ng * n)])
    rsq_off = np.concatenate([[0], np.cumsum(n * n)])
    stage_of_col = np.repeat(np.arange(K + 1), n)

    rows, cols = (np.asarray(v, dtype=np.int64) for v in jac.get_triplet())
    k = stage_of_col[cols]
    c = cols - col[k]
    kind = np.full(rows.size, -1)
    index = np.zeros(rows.size, dtype=np.int64)
    in_ab = (rows >= row_ab[k]) & (rows < row_cd[k])
    in_cd = (rows >= row_cd[k]) & (rows < row_cd[k] + ng[k])
    prev = np.maximum(k - 1, 0)  # x_k in the gap rows of stage k - 1
    eye = (k > 0) & (c < nx[k]) & (rows == row_ab[prev] + c)
    kind[in_ab], index[in_ab] = 0, (ab_off[k] + c * gaps[k] + rows - row_ab[k])[in_ab]
    kind[in_cd], index[in_cd] = 1, (cd_off[k] + c * ng[k] + rows - row_cd[k])[in_cd]
    kind[eye] = 2
    if np.any(kind < 0):
        i = int(np.flatnonzero(kind < 0)[0])
        raise NotStaged(f"Jacobian entry ({rows[i]}, {cols[i]}) lies outside the stage blocks")

    h_rows, h_cols = (np.asarray(v, dtype=np.int64) for v in hess.get_triplet())
    hk = stage_of_col[h_cols]
    inside = stage_of_col[h_rows] == hk
    h_index = np.where(inside, rsq_off[hk] + (h_cols - col[hk]) * n[hk] + h_rows - col[hk], -1)
    return BlockMaps(col[:-1], row_ab, row_cd, ab_off, cd_off, rsq_off, kind, index, h_index)


def _ints(a: Any) -> np.ndarray:
    return np.ascontiguousarray(a, dtype=np.intc)


def _doubles(a: Any) -> np.ndarray:
    return np.ascontiguousarray(np.ravel(a), dtype=float)


def _fill(array: np.ndarray, value: Any) -> None:
    """Copy the numbers of ``value`` into ``array``, which has as many."""
    value = np.ravel(value)
    if value.size != array.size:
        raise ValueError(f"fatrop's driver expects {array.size} numbers, got {value.size}")
    array[:] = value


def _ptr(a: np.ndarray, kind: Any) -> Any:
    return a.ctypes.data_as(kind)


class FatropOcp:
    """fatrop on a stage form through its C interface, with the five Functions
    ``functions`` (their names :data:`~ocgroupoid.nlp.jit.NLP_FUNCTIONS`): compiled into
    ``library``, or evaluated by CasADi (:class:`Buffers`) without one; with fatrop's
    ``options``. :meth:`solve` runs it."""

    def __init__(self, sf: StageForm, functions: dict[str, ca.Function], library: Path | None,
                 options: dict[str, Any]) -> None:
        jac = functions["nlp_jac_g"].sparsity_out(1)
        hess = functions["nlp_hess_l"].sparsity_out(1)
        for name, fn in functions.items():  # the driver reads and writes dense vectors
            for i in range(fn.n_out()):
                if not (fn.sparsity_out(i).is_dense() or (name, i) in
                        (("nlp_jac_g", 1), ("nlp_hess_l", 1))):
                    raise NotStaged(f"{name} output {i} is not dense")
        maps = block_maps(sf, jac, hess)
        self.form, self.n_rows = sf, sf.order.size
        self._lib = driver()
        #: whether its solves can be guarded in the caller's process (``fatrop_guard.c``:
        #: Linux on x86-64 or AArch64, with a real-time signal free for its timer)
        self.guardable = bool(self._lib.ocg_guard_available())
        #: the compiled Functions' library, or None (CasADi evaluates them)
        self.library = library
        kinds = option_kinds(options)
        arrays = {name: _ints(v) for name, v in (
            ("nx", sf.nx), ("nu", sf.nu), ("ng", sf.ng), ("col", maps.col),
            ("row_ab", maps.row_ab), ("row_cd", maps.row_cd), ("ab_off", maps.ab_off),
            ("cd_off", maps.cd_off), ("rsq_off", maps.rsq_off), ("a_kind", maps.a_kind),
            ("a_index", maps.a_index), ("h_index", maps.h_index))}
        names = [name.encode() for name in options]
        strings = [str(v).encode() if kinds[k] == STRING else b"" for k, v in options.items()]
        kind_array = _ints([kinds[k] for k in options])
        values = _doubles([0.0 if kinds[k] == STRING else float(v) for k, v in options.items()])
        p = _Problem()
        p.K, p.nz, p.n_rows = sf.K, sf.nz, self.n_rows
        p.nnz_a, p.nnz_h = jac.nnz(), hess.nnz()
        p.n_ab, p.n_cd, p.n_rsq = (int(offsets[-1]) for offsets in
                                   (maps.ab_off, maps.cd_off, maps.rsq_off))
        for name, value in arrays.items():
            setattr(p, name, _ptr(value, _INT_P))
        self._code = ctypes.CDLL(str(library)) if library is not None else None
        if self._code is not None:
            for i, name in enumerate(NLP_FUNCTIONS):
                p.eval[i] = ctypes.cast(getattr(self._code, name), ctypes.c_void_p)
                p.work[i] = ctypes.cast(getattr(self._code, f"{name}_work"), ctypes.c_void_p)
        else:
            #: CasADi's evaluation of the Functions (:class:`Buffers`), kept alive with p
            self._buffers = [Buffers(functions[name]) for name in NLP_FUNCTIONS]
            p.buffer_eval = buffer_eval()
            for i, b in enumerate(self._buffers):
                p.buffer[i] = b.address
                for j, a in enumerate(b.inputs):
                    p.buffer_in[i][j] = a.ctypes.data
                    p.buffer_n_in[i][j] = b.sizes[j]
                for j, a in enumerate(b.outputs):
                    p.buffer_out[i][j] = a.ctypes.data
        c_names = (ctypes.c_char_p * len(names))(*names)
        c_strings = (ctypes.c_char_p * len(strings))(*strings)
        p.n_options = len(options)
        p.option_names, p.option_strings = c_names, c_strings
        p.option_kinds = _ptr(kind_array, _INT_P)
        p.option_values = _ptr(values, _DOUBLE_P)
        p.max_iter = int(options.get("max_iter", FATROP_MAX_ITER))
        #: what the C struct points into, kept alive with it
        self._keep = (arrays, kind_array, values, c_names, c_strings)
        self._problem = p
        context = self._lib.ocg_context_new(ctypes.byref(p))
        if not context:
            raise MemoryError("fatrop's driver could not allocate its work memory")
        self._context = context
        weakref.finalize(self, self._lib.ocg_context_free, context)
        self._last: _Solve | None = None
        #: the stop request of the guarded solve under way, asked through :attr:`_check`
        self._stop: Callable[[], bool] = never
        self._raised: list[BaseException] = []
        self._check = _CHECK(self._ask)
        #: the listener of the solve under way, heard through :attr:`_iteration`
        self._listener: Callable[[int, float, float], bool] | None = None
        self._iteration = _ITERATION(self._hear)
        self._lock = threading.Lock()
        #: the non-finite evaluations of the last guarded solve
        self.nans = 0
        #: a solve's arrays (:data:`SOLVE_ARRAYS`), allocated once: inputs copied in, outputs
        #: copied out (fresh arrays and their addresses cost 30 us a solve)
        nz, n_rows = sf.nz, self.n_rows
        n_q = functions["nlp_f"].nnz_in(1)
        self._inputs = [np.zeros(n) for n in (nz, n_q, nz, nz, n_rows, n_rows)]
        whole = np.zeros(2 * nz + 2 * n_rows + 1)
        self._outputs = dict(zip(("x", "g", "lam_g", "lam_x", "f"), np.split(
            whole, np.cumsum([nz, n_rows, n_rows, nz]))))
        self._addresses = tuple(a.ctypes.data for a in (*self._inputs, *self._outputs.values()))

    def _ask(self) -> int:
        """The guarded solve's question to its caller: stop? (An exception, such as
        KeyboardInterrupt on a second Ctrl-C, stops it and is raised once it has returned.)"""
        try:
            return int(bool(self._stop()))
        except BaseException as err:  # noqa: BLE001  (raised again by solve)
            self._raised.append(err)
            return 1

    def _hear(self, k: int, objective: float, infeasibility: float) -> int:
        """fatrop's iteration k, told to the listener of the solve under way: stop? (An
        exception stops fatrop as well and is raised once it has returned.)"""
        try:
            return int(bool(self._listener is not None
                            and self._listener(k, objective, infeasibility)))
        except BaseException as err:  # noqa: BLE001  (raised again by solve)
            self._raised.append(err)
            return 1

    @property
    def times(self) -> SolveTimes | None:
        """The last solve's times (:class:`SolveTimes`), None before the first; read from
        the driver's record of that solve when asked, not at every solve."""
        s = self._last
        if s is None:
            return None
        return SolveTimes(s.solve_seconds, dict(zip(NLP_FUNCTIONS, s.seconds)),
                          dict(zip(NLP_FUNCTIONS, s.calls)))

    def solve(self, z0: Any, q: Any, lbg: Any, ubg: Any, lbz: Any, ubz: Any,
              guard: Guard | None = None,
              listener: Callable[[int, float, float], bool] | None = None
              ) -> tuple[dict[str, np.ndarray], int, int, int, bool] | Stopped:
        """fatrop from z0 with parameters q and the stage form's bounds: the solution
        ``x, f, g, lam_g, lam_x`` (stage form, scaled as the Functions are), its
        iterations, fatrop's return flag, its return value (0: converged) and whether the
        ``listener`` stopped it. ``listener(k, objective, infeasibility)`` hears the start of
        each iteration k (k done; the objective and the largest violation of a bound at the
        iterate, scaled as the Functions are) and stops fatrop by returning True: fatrop ends
        that iteration with its step and stops (max_iter set to k: k + 1 iterations, the
        last iterate kept). With a ``guard`` (where :attr:`guardable`),
        :class:`~ocgroupoid.nlp.isolated.Stopped` when it was left (:class:`Guard`), fatrop's
        solver abandoned; :class:`Unavailable` when the guard's timer could not be created."""
        with self._lock:  # one solve at a time: the driver's memory and solver are shared
            for array, value in zip(self._inputs, (z0, q, lbz, ubz, lbg, ubg)):
                _fill(array, value)
            s = _Solve(*self._addresses)
            if guard is not None:
                s.guarded, s.every = 1, guard.every
                s.nan_limit = min(guard.nan_limit, 2**31 - 1)
                s.limit = guard.seconds if math.isfinite(guard.seconds) else 7 * 86400.0
                s.watch_sigint = threading.current_thread() is threading.main_thread()
                s.check = self._check
                self._stop = guard.stop
            if listener is not None:
                s.iteration, self._listener = self._iteration, listener
            try:
                self._lib.ocg_fatrop_solve(self._context, ctypes.byref(s))
            finally:
                self._stop, self._listener = never, None
            raised, self._raised = self._raised, []
            self._last, self.nans = s, s.nans
            out = {name: v.copy() for name, v in self._outputs.items()}
        if raised:
            raise raised[0]
        if s.left < 0:
            raise Unavailable("fatrop's guard could not create its timer")
        if s.left:
            return Stopped(LEFT[s.left])
        if s.bad_structure:
            raise NotStaged("a gap row's coefficient on x_{k+1} is not 1")
        return out, s.iterations, s.return_flag, s.status, s.stopped_at >= 0
