"""Plots with one unit per panel (issue 29): every panel of every problem file's figure holds
components of one unit, named on its y axis; bounds are drawn where the problem has them; a
figure of ten controls stays readable (no legend over any axes). Units come from
``Problem.control(..., unit=)``, ``Problem.describe(..., group=)``, a problem file's
``definition.describe`` and the defaults of each factor; read back from the axes drawn.

The solutions are cheap (N = 6, at most 30 IPOPT iterations, one start): a figure needs the
labels and some trajectories, not an optimum.
"""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

import casadi as ca
import matplotlib
import numpy as np
import pytest

import ocgroupoid as og
from ocgroupoid import files
from ocgroupoid.errors import ConfigError
from ocgroupoid.systems.quadrotor import quadrotor

matplotlib.use("Agg")

ROOT = Path(__file__).resolve().parent.parent
FILES = sorted((ROOT / "problems").glob("*.yaml"))
TEN = ROOT / "tests" / "data" / "ten_controls.yaml"
N = 6


def cheap(path: Path) -> og.Solution:
    """A solution of a problem file at N = 6 after at most 30 iterations (not verified)."""
    cfg = files.load(path, [f"horizon.N={N}", "solver.ipopt.max_iter=30"])
    f, d = cfg.file, cfg.file.discretization
    solver = og.compile_problem(files.build(cfg), N, d.retraction, d.rule, f.solver.ipopt, d.scheme,
                        d.steps)
    return solver.solve(multistart=False)


@pytest.fixture(scope="module")
def solutions() -> dict[str, og.Solution]:
    return {p.stem: cheap(p) for p in [*FILES, TEN]}


@pytest.fixture(scope="module")
def figures(solutions: dict[str, og.Solution]) -> dict[str, Any]:
    """The figure of every solution (not drawn: what the axes hold, not where)."""
    return {name: og.plot(sol) for name, sol in solutions.items()}


def drawn(sol: og.Solution) -> Any:
    """The figure of a solution, laid out (legends and axes at their places, no pixels)."""
    fig = og.plot(sol)
    fig.draw_without_rendering()
    return fig


def unit_of(sol: og.Solution, gid: str) -> str:
    """The declared unit of the component a line stands for, from its gid (``controls[3]``,
    ``velocity:xi[4]``, ``position:g[0]``, ``multipliers:Phi[2]``...) and the labels."""
    m = re.fullmatch(r"(\w+)(?::(\w+))?\[(\d+)\]", gid)
    assert m, gid
    kind, name, i = m.group(1), m.group(2), int(m.group(3))
    labels = sol.labels
    if kind == "controls":
        return labels["controls"]["units"][i]
    section = {"state": "states", "velocity": "velocities", "multipliers": "multipliers",
               "position": "states", "heading": "states"}[kind]
    if name not in labels[section]:  # an undescribed constraint: its multipliers
        return ""
    units = labels[section][name]["units"]
    return units[i + 3] if kind == "position" else units[i]


def component_lines(ax: Any) -> list[Any]:
    return [ln for ln in ax.get_lines() if re.fullmatch(r"[\w:]+\[\d+\]", ln.get_gid() or "")]


def suffix(unit: str) -> str:
    return "[-]" if unit == "1" else f"[{unit}]"


# ------------------------------------------------------------------ one unit per panel


@pytest.mark.parametrize("name", [p.stem for p in FILES] + [TEN.stem])
def test_every_panel_holds_one_unit_named_on_its_axis(name: str,
                                                      solutions: dict[str, og.Solution],
                                                      figures: dict[str, Any]) -> None:
    sol = solutions[name]
    for ax in figures[name].axes:
        units = {unit_of(sol, ln.get_gid()) for ln in component_lines(ax)}
        assert len(units) <= 1, (ax.get_title(), units)
        if units and units != {""}:
            assert ax.get_ylabel().endswith(suffix(units.pop())), ax.get_ylabel()


@pytest.mark.parametrize("name", [p.stem for p in FILES])
def test_states_velocities_and_controls_declare_their_units(name: str) -> None:
    """Every problem file's states, velocities and controls have units (declared or by the
    defaults of their factors), so that no two quantities share a panel by accident."""
    labels = files.build(files.load(ROOT / "problems" / f"{name}.yaml", [])).labels()
    for kind in ("states", "velocities"):
        for qname, d in labels[kind].items():
            assert all(d["units"]), (kind, qname, d["units"])
    assert all(labels.get("controls", {}).get("units", [])), labels.get("controls")


def test_the_quadrotor_draws_thrust_and_torques_apart(figures: dict[str, Any]) -> None:
    ax = {a.get_gid(): a for a in figures["quadrotor"].axes}
    thrust, torques = ax["controls:N"], ax["controls:N m"]
    assert (thrust.get_title(), thrust.get_ylabel()) == ("thrust along body z", "f [N]")
    assert (torques.get_title(), torques.get_ylabel()) == ("body torques", "tau [N m]")
    assert [ln.get_label() for ln in component_lines(torques)] == \
        [f"torque τ{i} about body {a}" for i, a in zip("123", "xyz")]
    lo, hi = torques.get_ylim()  # the torques fill their panel: readable
    assert hi - lo < 1.5 * 2 * 0.5
    rotation, translation = ax["multipliers:Phi:rotation:"], ax["multipliers:Phi:translation:"]
    assert rotation.get_title() == "multipliers of equations of motion: rotation"
    assert len(component_lines(rotation)) == len(component_lines(translation)) == 3


# ------------------------------------------------------------------ bounds


@pytest.mark.parametrize("name", [p.stem for p in FILES] + [TEN.stem])
def test_bounds_are_drawn_where_the_problem_has_them(name: str,
                                                     solutions: dict[str, og.Solution],
                                                     figures: dict[str, Any]) -> None:
    """Every side of every bound on a control, a velocity or a vector state component is a
    dashed line in a panel of that component (off scale only when far from the values, and
    then said in the legend)."""
    sol, fig = solutions[name], figures[name]
    for b in sol.labels["bounds"]:
        if b["quantity"] is None:
            continue
        gid = {"controls": "controls", "velocities": f"velocity:{b['of']}",
               "states": f"state:{b['of']}"}[b["quantity"]] + f"[{b['index']}]"
        (ax,) = [a for a in fig.axes if any(ln.get_gid() == gid for ln in a.get_lines())]
        values = {ln.get_ydata()[0] for ln in ax.get_lines() if ln.get_gid() == "bound"}
        for side in ("lower", "upper"):
            if b[side] is not None:
                assert any(v == pytest.approx(b[side]) for v in values), (gid, side, values)
        legend = [t.get_text() for t in ax.get_legend().get_texts()]
        assert any(t.startswith("bounds") for t in legend), legend


def test_bound_labels_follow_each_solve_s_parameters_and_are_its_own() -> None:
    """The labels of a compiled problem's solutions (kept between solves with the same
    parameters) give the sides at each solve's parameter values, and one solution's labels
    changed leave the next solution's alone."""
    cfg = files.load(Path(__file__).resolve().parents[1] / "problems" / "reaction_wheels.yaml",
                     ["horizon.N=8"])
    d = cfg.file.discretization
    compiled = og.compile_problem(files.build(cfg), cfg.file.horizon.N, d.retraction, d.rule,
                                  cfg.file.solver.ipopt, d.scheme, d.steps)

    def torque_sides(sol: og.Solution) -> set[tuple[float, float]]:
        return {(b["lower"], b["upper"]) for b in sol.labels["bounds"] if b["name"] == "u"}

    first = compiled.solve(multistart=False, replay=False)
    assert torque_sides(first) == {(-0.1, 0.1)}
    first.labels["bounds"].clear()
    assert torque_sides(compiled.solve(multistart=False, replay=False)) == {(-0.1, 0.1)}
    wider = compiled.solve(params={"tau_max": 0.12}, multistart=False, replay=False)
    assert torque_sides(wider) == {(-0.12, 0.12)}


def test_a_bound_far_from_the_values_is_drawn_off_scale_and_said(figures: dict[str, Any]
                                                                 ) -> None:
    ax = {a.get_gid(): a for a in figures["ten_controls"].axes}
    hand = ax["controls:hand:N m"]
    values = np.concatenate([ln.get_ydata() for ln in component_lines(hand)])
    lo, hi = hand.get_ylim()
    assert lo <= np.nanmin(values)
    assert np.nanmax(values) <= hi < 10.0
    assert "bounds (off scale: -10, 10)" in [t.get_text() for t in hand.get_legend().get_texts()]


# ------------------------------------------------------------------ ten controls


def overlaps(a: Any, b: Any) -> bool:
    return a.x0 < b.x1 and b.x0 < a.x1 and a.y0 < b.y1 and b.y0 < a.y1


def assert_legends_clear(fig: Any) -> None:
    """No legend over any axes (its own included) and every legend inside the figure."""
    boxes = {ax.get_gid(): ax.get_window_extent() for ax in fig.axes}
    page = fig.bbox
    for ax in fig.axes:
        legend = ax.get_legend()
        if legend is None:
            continue
        box = legend.get_window_extent()
        hit = [gid for gid, b in boxes.items() if overlaps(box, b)]
        assert not hit, (ax.get_gid(), hit)
        assert page.x0 <= box.x0 and box.x1 <= page.x1 and page.y0 <= box.y0 and \
            box.y1 <= page.y1, (ax.get_gid(), box, page)


def test_ten_controls_get_one_panel_per_group_and_unit(solutions: dict[str, og.Solution]
                                                       ) -> None:
    fig = drawn(solutions["ten_controls"])
    controls = [a for a in fig.axes if a.get_gid().startswith("controls")]
    assert [(a.get_title(), a.get_ylabel()) for a in controls] == [
        ("forces and joint torques: carriage", "u [N]"),
        ("forces and joint torques: arm", "u [N m]"),
        ("forces and joint torques: hand", "u [N m]")]
    assert sum(len(component_lines(a)) for a in controls) == 10
    assert_legends_clear(fig)


def test_ten_controls_in_one_panel_stay_readable(solutions: dict[str, og.Solution]) -> None:
    """Ten controls of one unit and group: one panel, ten distinct colours, a legend entry
    each, beside the axes."""
    data = json.loads(solutions["ten_controls"].to_json())
    data["labels"]["controls"].pop("groups")
    data["labels"]["controls"]["units"] = ["N"] * 10
    fig = drawn(og.Solution.from_json(json.dumps(data)))
    (ax,) = [a for a in fig.axes if a.get_gid().startswith("controls")]
    lines = component_lines(ax)
    assert len(lines) == 10 and len({ln.get_color() for ln in lines}) == 10
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert labels[:10] == data["labels"]["controls"]["components"]
    assert_legends_clear(fig)


@pytest.mark.parametrize("name", ["quadrotor", "plate_ball"])  # the longest legend labels
def test_no_legend_covers_an_axes(name: str, solutions: dict[str, og.Solution]) -> None:
    assert_legends_clear(drawn(solutions[name]))


def test_every_panel_against_time_shares_the_time_axis(figures: dict[str, Any]) -> None:
    fig = figures["quadrotor"]
    timed = [a for a in fig.axes if a.get_xlabel().startswith("time")]
    assert len(timed) > 4
    assert all(a.get_shared_x_axes().joined(timed[0], a) for a in timed)


# ------------------------------------------------------------------ declaring units


def test_a_control_declares_its_unit_meaning_and_group() -> None:
    pb = quadrotor()
    controls = pb.labels()["controls"]
    assert controls["units"] == ["N", "N m", "N m", "N m"]
    assert controls["symbols"] == ["f", "tau", "tau", "tau"]
    assert controls["meanings"] == {"f": "thrust along body z", "tau": "body torques"}
    pb = og.Problem(og.LieGroupFactor(og.SE3, state="g", velocity="xi"))
    tau = pb.control("tau", 3, unit="N m", group=["roll and pitch"] * 2 + ["yaw"])
    xi = pb.velocity("xi")
    pb.mechanics(0.5 * ca.dot(xi, xi), actuated="xi", force=ca.vertcat(tau, 0, 0, 0))
    assert pb.labels()["controls"]["groups"] == ["roll and pitch", "roll and pitch", "yaw"]
    with pytest.raises(ConfigError, match=r"tau2 has 3 components, got 2 units"):
        og.Problem(og.LieGroupFactor(og.SE3, state="g", velocity="xi")).control(
            "tau2", 3, unit=["N m", "N m"])


def test_a_problem_file_declares_the_units_of_controls_of_their_own() -> None:
    """``controls: {f: 1, tau: 3}`` described by name: the built-in quadrotor's units."""
    labels = files.build(files.load(ROOT / "tests" / "data" / "custom_quadrotor.yaml", [])
                         ).labels()["controls"]
    assert labels["units"] == quadrotor().labels()["controls"]["units"]
    assert labels["meanings"] == {"f": "thrust along body z", "tau": "body torques"}


def test_undeclared_units_default_by_factor() -> None:
    """A rotation in rad and rad/s, a pose's translation in m and m/s, a vector state's
    velocity in its state's unit per time unit (minutes here)."""
    G = og.Groupoid(og.LieGroupFactor(og.SE3, state="g", velocity="xi"),
                    og.Pair(2, state="x", velocity="dx"))
    pb = og.Problem(G)
    pb.describe("x", "cart positions", "km")
    pb.describe("t", "time", "min")
    labels = pb.labels()
    assert labels["states"]["g"]["units"] == ["rad"] * 3 + ["m"] * 3
    assert labels["velocities"]["xi"]["units"] == ["rad/min"] * 3 + ["m/min"] * 3
    assert labels["velocities"]["dx"] == {"meaning": "rate of the cart positions",
                                          "components": ["dx1", "dx2"],
                                          "units": ["km/min", "km/min"]}


@pytest.mark.parametrize("entry, message", [
    ("{meaning: force, unit: ''}", r"a unit is non-blank text"),
    ("{meaning: force, unit: N, group: ['']}", r"a group is non-blank text"),
    ("{meaning: force, unit: N, group: [a, b]}", r"F has 1 component, got 2 groups"),
    ("{meaning: force, unit: N, grup: a}", r"unknown key 'definition\.describe\.F\.grup'"),
])
def test_a_problem_file_checks_units_and_groups(entry: str, message: str,
                                                tmp_path: Path) -> None:
    text = (ROOT / "problems" / "cart_pole.yaml").read_text().replace(
        "F: {meaning: force on the cart, unit: N}", f"F: {entry}")
    bad = tmp_path / "bad.yaml"
    bad.write_text(text)
    with pytest.raises(ConfigError, match=message):
        files.build(files.load(bad, []))
