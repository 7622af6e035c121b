"""Plots for engineers (issue 15): what the figure of a Solution says, read back from its
matplotlib axes — units from the model, one legend entry per component, the attitude error
to the target, x-y paths with start and target, bounds; names and units declared through
``Problem.describe`` (and a problem file's ``definition.describe``) and carried by the
solution file, the exported C solver's included; old files without labels still plot.
"""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path
from typing import Any

import casadi as ca
import matplotlib
import numpy as np
import pytest
from typer.testing import CliRunner

import ocgroupoid as og
from ocgroupoid import files
from ocgroupoid.cli import app
from ocgroupoid.errors import ConfigError
from ocgroupoid.export.codegen import export_c
from ocgroupoid.systems.rigid_body import rigid_body

from .dubins_exact import CASES

matplotlib.use("Agg")

from .cbuild import CFLAGS_QUICK  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
PROBLEMS = ROOT / "problems"
N = 12


def solve_file(name: str, *sets: str) -> og.Solution:
    """A problem file solved at N = 12 from the first guess (no multi-start: fast)."""
    cfg = files.load(PROBLEMS / f"{name}.yaml", [f"horizon.N={N}", *sets])
    f, d = cfg.file, cfg.file.discretization
    solver = og.compile_problem(files.build(cfg), f.horizon.N, d.retraction, d.rule, f.solver.ipopt,
                        d.scheme, d.steps)
    sol = solver.solve(multistart=False)
    assert sol.success, sol.status
    return sol


@pytest.fixture(scope="module")
def slew() -> og.Solution:
    return solve_file("so3_rest_to_rest")


@pytest.fixture(scope="module")
def plate_ball() -> og.Solution:
    return solve_file("plate_ball")


@pytest.fixture(scope="module")
def cart_pole() -> og.Solution:
    return solve_file("cart_pole", "horizon.N=24")  # converges from the first guess at 24


@pytest.fixture(scope="module")
def unicycle() -> og.Solution:
    """The Dubins car on SE(2), nothing described: unit forward speed, no sideslip, |ω| <= 1,
    minimum time from the origin to the LSL case of :mod:`tests.dubins_exact`."""
    pb = og.Problem(og.LieGroupFactor(og.SE2, state="g", velocity="xi"), name="dubins",
                    order=1)
    xi = pb.velocity("xi")  # (ω, v_x, v_y)
    pb.subject_to(xi[1:] - ca.vertcat(1.0, 0.0), name="unicycle")
    pb.bound(xi[0], -1.0, 1.0, name="turn")
    pb.report_controls(xi[0], ["omega"])
    pb.minimize_time()
    (x, y, theta), _ = CASES["LSL"]
    pb.initial(g=og.se2.from_spec({"angle": 0.0, "position": [0.0, 0.0]}))
    pb.final(g=og.se2.from_spec({"angle": theta, "position": [x, y]}))
    pb.horizon(6.0, free=True, T_min=1.0, T_max=20.0)
    sol = og.solve(pb, N=8, scheme="order4")
    assert sol.success, sol.status
    return sol


def axes_by_gid(fig: Any) -> dict[str, Any]:
    return {ax.get_gid(): ax for ax in fig.axes}


def legend_labels(ax: Any) -> list[str]:
    legend = ax.get_legend()
    return [t.get_text() for t in legend.get_texts()] if legend else []


def lines(ax: Any, gid: str) -> list[Any]:
    return [ln for ln in ax.get_lines() if ln.get_gid() == gid]


def data_scales(ax: Any) -> np.ndarray:
    """Pixels per unit of x and of y as drawn (the axes' aspect is applied at drawing)."""
    p = ax.transData.transform([[0.0, 0.0], [1.0, 1.0]])
    return p[1] - p[0]


def described(sol: og.Solution, name: str, meaning: str) -> og.Solution:
    """A copy of a solution whose SE(2) state ``name`` is described as ``meaning``."""
    copy = og.Solution.from_json(sol.to_json())
    pose = {"meaning": meaning, "components": ["heading", "x", "y"], "units": ["rad", "m", "m"]}
    copy.labels = {**copy.labels, "states": {**copy.labels.get("states", {}), name: pose}}
    return copy


def assert_no_empty_axes(fig: Any) -> None:
    for ax in fig.axes:
        drawn = [ln for ln in ax.get_lines() if np.isfinite(np.asarray(ln.get_ydata(),
                                                                       dtype=float)).any()]
        assert drawn, f"empty panel {ax.get_title()!r}"
        assert ax.get_xlabel() and ax.get_ylabel() and ax.get_title(), ax.get_title()


# ------------------------------------------------------------------ the figure's content


def test_units_and_legends_come_from_the_model(slew: og.Solution) -> None:
    fig = og.plot(slew)
    ax = axes_by_gid(fig)
    omega, u = ax["velocity:Omega"], ax["controls"]
    assert omega.get_ylabel() == "Omega [rad/s]" and u.get_ylabel() == "u [rad/s²]"
    assert omega.get_xlabel() == "time t [s]"
    assert legend_labels(omega) == [f"Ω{i} about body axis {i}" for i in (1, 2, 3)] + ["target"]
    assert legend_labels(u) == [f"u{i} about body axis {i}" for i in (1, 2, 3)]
    for a in fig.axes:
        labels = legend_labels(a)
        assert len(labels) == len(set(labels)), labels
    assert_no_empty_axes(fig)


def test_rigid_body_shows_the_attitude_error_reaching_zero(slew: og.Solution) -> None:
    ax = axes_by_gid(og.plot(slew))["attitude-error:R"]
    assert "error to the target" in ax.get_title() and "[deg]" in ax.get_ylabel()
    error = lines(ax, "attitude-error:R")[0].get_ydata()
    assert error[0] == pytest.approx(np.degrees(2.5), abs=1e-6)  # the slew's angle
    assert abs(error[-1]) < 1e-6
    assert lines(ax, "target"), "the target is marked"


def test_a_missed_target_is_said(slew: og.Solution) -> None:
    missed = og.Solution.from_json(slew.to_json())
    missed.diagnostics = {**missed.diagnostics, "final_residual": {"R": 0.1}}
    ax = axes_by_gid(og.plot(missed))["attitude-error:R"]
    assert ax.get_title() == "attitude R: error to the final attitude reached (5.7° off the " \
        "target)"
    assert not lines(ax, "target")  # no star where the target is not


def test_plate_ball_draws_the_xy_path_with_start_and_target(plate_ball: og.Solution) -> None:
    fig = og.plot(plate_ball)
    ax = axes_by_gid(fig)["path:xy"]
    xy = plate_ball.states["xy"]
    (start,), (target,) = lines(ax, "start"), lines(ax, "target")
    np.testing.assert_allclose(np.ravel(start.get_data()), xy[0], atol=1e-12)
    np.testing.assert_allclose(np.ravel(target.get_data()), [1.0, 0.5], atol=1e-8)
    assert (ax.get_xlabel(), ax.get_ylabel()) == ("x [m]", "y [m]")
    assert legend_labels(ax) == ["path", "start", "target"]
    assert ax.get_aspect() == 1.0
    rolling = [a for a in fig.axes if a.get_gid().startswith("multipliers:rolling")]
    assert sum(len(legend_labels(a)) for a in rolling) == 3  # one entry per constraint row
    assert_no_empty_axes(fig)


@pytest.mark.parametrize("case, stretch", [("unicycle", 1.0), ("unicycle", 20.0),
                                           ("plate_ball", 1.0)])
def test_paths_in_the_plane_are_drawn_on_equal_scales(case: str, stretch: float,
                                                      request: pytest.FixtureRequest,
                                                      tmp_path: Path) -> None:
    """An arc is drawn as an arc of a circle: as many pixels per metre along x as along y
    in the PNG written; a long, flat path (x stretched 20 times) widens the y range rather
    than squash the y axis."""
    sol = og.Solution.from_json(request.getfixturevalue(case).to_json())
    if case == "unicycle":
        sol.states["g"][:, 0, 2] *= stretch
    fig = og.plot(sol, tmp_path / "path.png")  # drawn: the aspect is applied
    (ax,) = [a for a in fig.axes if a.get_gid().startswith("path:")]
    assert ax.get_aspect() == 1.0 and ax.get_adjustable() == "datalim"
    px, py = data_scales(ax)
    assert px == pytest.approx(py, rel=1e-9), (px, py)
    (path,) = [ln for ln in ax.get_lines() if ln.get_gid() == ax.get_gid()]
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    assert x0 <= np.min(path.get_xdata()) and np.max(path.get_xdata()) <= x1
    assert y0 <= np.min(path.get_ydata()) and np.max(path.get_ydata()) <= y1


def test_the_unicycle_path_ends_on_the_dubins_goal(unicycle: og.Solution) -> None:
    ax = axes_by_gid(og.plot(unicycle))["path:g"]
    (x, y, _), _ = CASES["LSL"]
    (start,), (target,) = lines(ax, "start"), lines(ax, "target")
    np.testing.assert_allclose(np.ravel(start.get_data()), [0.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(np.ravel(target.get_data()), [x, y], atol=1e-8)
    assert legend_labels(ax) == ["path", "start", "target"]


@pytest.mark.parametrize("case", ["unicycle", "plate_ball", "slew"])
def test_no_title_repeats_a_state_name(case: str, request: pytest.FixtureRequest) -> None:
    """A title names a state once: by its meaning and symbol ("pose g"), by its symbol alone
    when nothing is described ("g", not "g g"), also in a file written without labels."""
    sol = request.getfixturevalue(case)
    data = json.loads(sol.to_json())
    data.pop("labels")
    for version in (sol, og.Solution.from_json(json.dumps(data))):
        for ax in og.plot(version).axes:
            for name in sol.states:
                said = re.findall(rf"(?<!\w){re.escape(name)}(?!\w)", ax.get_title())
                assert len(said) <= 1, (name, ax.get_title())


def test_planar_titles_name_the_state_by_its_meaning(unicycle: og.Solution) -> None:
    titles = [a.get_title() for a in og.plot(unicycle).axes]
    assert titles[:2] == ["g: path in the plane", "g: heading"]
    titles = [a.get_title() for a in og.plot(described(unicycle, "g", "pose")).axes]
    assert titles[:2] == ["pose g: path in the plane", "pose g: heading"]
    titles = [a.get_title() for a in og.plot(described(unicycle, "g", "pose g of the car")).axes]
    assert titles[:2] == ["pose g of the car: path in the plane", "pose g of the car: heading"]


def test_bounds_are_drawn_on_bounded_controls(cart_pole: og.Solution) -> None:
    fig = og.plot(cart_pole)
    ax = axes_by_gid(fig)
    force = ax["controls"]
    assert force.get_ylabel() == "F [N]" and force.get_title() == "force on the cart"
    assert sorted(ln.get_ydata()[0] for ln in lines(force, "bound")) == [-10.0, 10.0]
    assert "bounds" in legend_labels(force)
    assert sorted(ln.get_ydata()[0] for ln in lines(ax["state:x"], "bound")) == [-1.0, 1.0]
    assert_no_empty_axes(fig)


def test_a_free_final_time_is_marked() -> None:
    sol = solve_file("so3_minimum_time")
    fig = og.plot(sol)
    marks = [ln for a in fig.axes for ln in a.get_lines() if ln.get_gid() == "final-time"]
    assert len(marks) == len(fig.axes)
    assert all(ln.get_xdata()[0] == pytest.approx(sol.T) for ln in marks)
    assert "(free)" in fig.get_suptitle()


def test_old_files_without_labels_still_plot(slew: og.Solution, tmp_path: Path) -> None:
    data = json.loads(slew.to_json())
    for key in ("labels", "manifolds"):
        data.pop(key)
    old = og.Solution.from_json(json.dumps(data))
    fig = og.plot(old, tmp_path / "old.png")
    assert (tmp_path / "old.png").stat().st_size > 10_000
    ax = axes_by_gid(fig)
    assert legend_labels(ax["velocity:Omega"])[:3] == ["Omega1", "Omega2", "Omega3"]
    assert legend_labels(ax["controls"]) == ["u1", "u2", "u3"]
    assert "attitude-error:R" in ax  # a 3 x 3 state is a rotation
    assert_no_empty_axes(fig)


# ------------------------------------------------------------------ API, CLI, C


def test_plot_and_solution_plot_return_a_figure_and_write_a_png(slew: og.Solution,
                                                               tmp_path: Path) -> None:
    from matplotlib.figure import Figure

    assert isinstance(og.plot(slew), Figure)
    fig = slew.plot(tmp_path / "sol.png")
    assert isinstance(fig, Figure)
    assert (tmp_path / "sol.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_cli_plot_and_solve_plot_draw_the_same_figure(slew: og.Solution, tmp_path: Path
                                                      ) -> None:
    runner = CliRunner()
    sol_json = tmp_path / "sol.json"
    slew.to_json(sol_json)
    r = runner.invoke(app, ["plot", str(sol_json), "--out", str(tmp_path / "a.png")])
    assert r.exit_code == 0, r.output
    r = runner.invoke(app, ["solve", str(PROBLEMS / "so3_rest_to_rest.yaml"), "--set",
                            f"horizon.N={N}", "--plot", str(tmp_path / "b.png"), "--quiet"])
    assert r.exit_code == 0, r.output
    assert (tmp_path / "a.png").stat().st_size > 10_000
    assert (tmp_path / "b.png").stat().st_size > 10_000


@pytest.mark.skipif(shutil.which("cc") is None or shutil.which("make") is None,
                    reason="no C compiler (cc) or make on PATH")
def test_the_exported_solver_writes_the_same_labels(tmp_path: Path) -> None:
    """Bounds that depend on parameters (``u: [-tau_max, tau_max]``) are written by their
    affine form, evaluated at the solution's parameters when plotted."""
    import subprocess

    cfg = files.load(PROBLEMS / "reaction_wheels.yaml", ["horizon.N=8"])
    f, d = cfg.file, cfg.file.discretization
    exp = export_c(files.build(cfg), tmp_path / "c", 8, d.retraction, d.rule, f.solver.ipopt,
                   build=True, scheme=d.scheme, cflags=CFLAGS_QUICK)
    py = exp.solver.solve(multistart=False)
    r = subprocess.run([str(exp.binary)], capture_output=True, text=True, timeout=120)
    c = og.Solution.from_json(r.stdout)
    for key in ("time", "states", "velocities", "controls", "multipliers", "final"):
        assert c.labels[key] == py.labels[key], key
    ax_c, ax_py = axes_by_gid(og.plot(c))["controls"], axes_by_gid(og.plot(py))["controls"]
    bounds = sorted(ln.get_ydata()[0] for ln in lines(ax_c, "bound"))
    assert bounds == sorted(ln.get_ydata()[0] for ln in lines(ax_py, "bound")) == [-0.1, 0.1]


# ------------------------------------------------------------------ describe


def test_describe_rejects_wrong_lengths_and_unknown_names() -> None:
    pb = rigid_body()
    with pytest.raises(ConfigError, match=r"Omega has 3 components, got 2 units"):
        pb.describe("Omega", "body rate", ["rad/s", "rad/s"])
    with pytest.raises(ConfigError, match=r"list of 3, got the string"):
        pb.describe("Omega", components="w")
    with pytest.raises(ConfigError, match=r"unknown name 'Omgea'; known: states \['R'\]"):
        pb.describe("Omgea", unit="rad/s")
    with pytest.raises(ConfigError, match="must differ"):
        pb.describe("Omega", components=["w", "w", "w"])
    pb.describe("t", "time since release", "min")
    assert pb.labels()["time"] == {"meaning": "time since release", "unit": "min"}


def test_a_problem_file_describe_is_checked_with_its_key(tmp_path: Path) -> None:
    text = (PROBLEMS / "cart_pole.yaml").read_text().replace(
        "F: {meaning: force on the cart, unit: N}", "F: {meaning: force, unit: [N, N]}")
    bad = tmp_path / "bad.yaml"
    bad.write_text(text)
    with pytest.raises(ConfigError, match=r"bad\.yaml:\d+: describe\('F'\): F has 1 component, "
                       r"got 2 units"):
        files.build(files.load(bad, []))
