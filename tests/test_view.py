"""The 3-D view (issue 29): the body moving along a solution as a self-contained HTML page, a
GIF or an MP4, for every kind of body (SO(3), SE(3), SE(2), the plate-ball, the heavy top).

Solutions are made here from known motions (no solve: fast), so the scene can be checked
against the motion itself. The page is loaded offline in a real headless Chromium (skipped
when none is installed): no errors, and screenshots at two times differ.
"""

from __future__ import annotations

import io
import json
import re
import shutil
from collections.abc import Callable
from html.parser import HTMLParser
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from typer.testing import CliRunner

import ocgroupoid as og
from ocgroupoid.cli import app
from ocgroupoid.errors import ConfigError, DependencyError
from ocgroupoid.plotting.scene import scene
from ocgroupoid.plotting.view import page

from .browser import Browser, find_chromium

T, NODES = 2.0, 33
OMEGA = np.array([0.4, -0.7, 1.1])  # body angular velocity of the known motions (rad/s)


def make(states: dict[str, Any], manifolds: dict[str, str], velocities: dict[str, Any]
         | None = None, parameters: dict[str, list[float]] | None = None,
         problem: str = "known_motion") -> og.Solution:
    """A Solution holding the given states at NODES times on [0, T]."""
    t = np.linspace(0.0, T, NODES)
    return og.Solution(
        problem=problem, success=True, status="Solve_Succeeded", N=NODES - 1, T=T, cost=1.0,
        iterations=1, solve_seconds=0.0, build_seconds=0.0, discretization={},
        parameters=parameters or {}, t=t, states={k: np.asarray(v) for k, v in states.items()},
        velocity_t=t, velocities={k: np.asarray(v) for k, v in (velocities or {}).items()},
        controls_t=t, controls=np.zeros((NODES, 0)), control_names=[], multipliers={},
        diagnostics={}, manifolds=manifolds)


def turning(t: np.ndarray) -> np.ndarray:
    """R(t) = exp(t hat(OMEGA)): a turn at a constant body angular velocity."""
    return Rotation.from_rotvec(np.outer(t, OMEGA)).as_matrix()


def so3() -> og.Solution:
    t = np.linspace(0.0, T, NODES)
    return make({"R": turning(t)}, {"R": "SO(3)"}, parameters={"inertia": [1.0, 2.0, 3.0]})


def se3() -> og.Solution:
    t = np.linspace(0.0, T, NODES)
    g = np.tile(np.eye(4), (NODES, 1, 1))
    g[:, :3, :3] = turning(t)
    g[:, :3, 3] = np.column_stack([np.cos(t), np.sin(t), 0.3 * t])  # a helix
    return make({"g": g}, {"g": "SE(3)"}, parameters={"J": [0.05, 0.05, 0.09]})


def se2() -> og.Solution:
    t = np.linspace(0.0, T, NODES)
    g = np.tile(np.eye(3), (NODES, 1, 1))
    g[:, 0, 0] = g[:, 1, 1] = np.cos(t)
    g[:, 1, 0], g[:, 0, 1] = np.sin(t), -np.sin(t)
    g[:, :2, 2] = np.column_stack([np.sin(t), 1 - np.cos(t)])  # a unit circle, heading along
    return make({"g": g}, {"g": "SE(2)"})


def ball() -> og.Solution:
    t = np.linspace(0.0, T, NODES)
    xy = np.column_stack([t, 0.5 * t ** 2])
    return make({"xy": xy, "R": turning(t)}, {"xy": "R^2", "R": "SO(3)"},
                parameters={"r": [0.5], "Omega_p": [0.8], "c": [0.0]})


def top() -> og.Solution:
    """The heavy top's reduced state: Gamma = R^T e3 of a known motion R = R0 exp(t hat Ω)."""
    t = np.linspace(0.0, T, NODES)
    R0 = Rotation.from_rotvec([0.4, 0.0, 0.0]).as_matrix()
    Gamma = np.einsum("fji,j->fi", R0 @ turning(t), [0.0, 0.0, 1.0])
    return make({"Gamma": Gamma, "theta": np.zeros((NODES, 2))},
                {"Gamma": "S^2", "theta": "R^2"},
                {"Omega": np.tile(OMEGA, (NODES, 1)), "dtheta": np.zeros((NODES, 2))},
                {"Ibar": [1.1, 1.2, 0.6], "J": [0.1, 0.1], "mgl": [1.0]})


BODIES: dict[str, Callable[[], og.Solution]] = {"so3": so3, "se3": se3, "se2": se2,
                                                 "ball": ball, "top": top}


class Tags(HTMLParser):
    """Every start tag with its attributes, and the text of the scene's script."""

    def __init__(self) -> None:
        super().__init__()
        self.tags: list[tuple[str, dict[str, str | None]]] = []
        self.scene = ""
        self._in_scene = False

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        self.tags.append((tag, dict(attrs)))
        self._in_scene = tag == "script" and dict(attrs).get("id") == "scene"

    def handle_data(self, data: str) -> None:
        if self._in_scene:
            self.scene += data

    def handle_endtag(self, tag: str) -> None:
        self._in_scene = False


@pytest.mark.parametrize("kind", BODIES)
def test_page_is_self_contained_and_holds_the_frames(kind: str) -> None:
    sol = BODIES[kind]()
    text = page(scene(sol, 50))
    parser = Tags()
    parser.feed(text)
    parser.close()
    loads = [(tag, a.get("src") or a.get("href")) for tag, a in parser.tags
             if a.get("src") or a.get("href")]
    assert all(str(url).startswith("data:") for _, url in loads), loads
    assert not re.search(r"(src|href)\s*=\s*[\"']?\s*(https?:)?//", text)
    assert not re.search(r"https?://", text), "the page names a network address"
    assert {"canvas", "input", "button", "select"} <= {tag for tag, _ in parser.tags}
    data = json.loads(parser.scene)
    assert data["kind"] == kind and len(data["t"]) == len(data["R"]) == len(data["p"]) == 50
    R = np.array(data["R"]).reshape(-1, 3, 3)
    assert np.allclose(R @ R.transpose(0, 2, 1), np.eye(3), atol=1e-5)
    assert [len(p) for p in data["paths"]] == [50] * len(data["traces"])
    assert len(text) < 100_000, f"the page is {len(text)} characters"


@pytest.mark.parametrize("kind", ["so3", "se3", "ball"])
def test_frames_pass_through_the_nodes(kind: str) -> None:
    """Sampled at the nodes' times, the scene is the solution's poses (the splines
    interpolate)."""
    sol = BODIES[kind]()
    sc = scene(sol, NODES)
    name = {"so3": "R", "se3": "g", "ball": "R"}[kind]
    R = sol.states[name][:, :3, :3]
    assert np.allclose(sc.R, R, atol=1e-12)
    if kind == "se3":
        assert np.allclose(sc.p, sol.states["g"][:, :3, 3], atol=1e-12)


def test_rotation_between_nodes_is_smooth() -> None:
    """Between the nodes of a constant-rate turn the spline is the turn itself."""
    sc = scene(so3(), 301)
    assert np.max(np.abs(sc.R - turning(sc.t))) < 1e-4


def test_top_turns_with_its_angular_velocity() -> None:
    """The top's attitude holds Gamma (R^T e3 = Gamma) and its spin about the vertical,
    integrated from Omega: the known motion R0 exp(t hat Omega) comes back."""
    sc = scene(top(), 81)
    R0 = Rotation.from_rotvec([0.4, 0.0, 0.0]).as_matrix()
    assert np.max(np.abs(sc.R - R0 @ turning(sc.t))) < 1e-3
    tip = sc.paths()[0]
    assert np.allclose(np.linalg.norm(tip, axis=1), np.linalg.norm(tip[0]))
    assert sc.pivot and np.allclose(sc.p, 0.0)


def test_ball_rolls_on_its_turning_plate() -> None:
    sol = ball()
    sc = scene(sol, NODES)
    contact = sc.paths()[0]
    assert np.allclose(contact[:, 2], 0.0) and np.allclose(sc.p[:, 2], 0.5)
    assert np.allclose(contact[:, :2], sol.states["xy"], atol=1e-12)
    assert sc.plate_angle is not None and np.isclose(sc.plate_angle[-1], 0.8 * T)


def test_a_body_the_view_does_not_know_is_refused() -> None:
    sol = make({"x": np.zeros((NODES, 1))}, {"x": "R^1"}, problem="cart")
    with pytest.raises(ConfigError, match=r"cart: no body to draw.*x \(R\^1\).*ocgroupoid plot"):
        scene(sol)


def test_a_failed_solution_is_refused() -> None:
    sol = so3()
    sol.states["R"][5] = np.nan
    with pytest.raises(ConfigError, match="the state R holds NaN"):
        scene(sol)


def test_api_writes_the_page(tmp_path: Path) -> None:
    out = og.view(so3(), tmp_path / "slew.html")
    assert out == tmp_path / "slew.html" and "<canvas" in out.read_text()


runner = CliRunner()


def test_cli_writes_a_page(tmp_path: Path) -> None:
    so3().to_json(tmp_path / "sol.json")
    r = runner.invoke(app, ["view", str(tmp_path / "sol.json"), "--out",
                            str(tmp_path / "slew.html"), "--frames", "40"])
    assert r.exit_code == 0, r.output
    data = Tags()
    data.feed((tmp_path / "slew.html").read_text())
    assert len(json.loads(data.scene)["t"]) == 40


@pytest.mark.parametrize("case, message", [
    ("extension", r"cannot write a view as \.png; give a file ending in \.html"),
    ("missing", r"no such file; give the JSON written by `ocgroupoid solve --out`"),
    ("invalid", r"not a solution file \(JSONDecodeError"),
    ("unknown", r"no body to draw"),
    ("no ffmpeg", r"writing \.mp4 needs ffmpeg on PATH: install it"),
])
def test_cli_errors_are_one_line(tmp_path: Path, case: str, message: str) -> None:
    src, out, env = tmp_path / "sol.json", tmp_path / "view.html", None
    so3().to_json(src)
    if case == "extension":
        out = tmp_path / "view.png"
    elif case == "missing":
        src = tmp_path / "nothing.json"
    elif case == "invalid":
        src.write_text("{not json")
    elif case == "unknown":
        make({"x": np.zeros((NODES, 1))}, {"x": "R^1"}).to_json(src)
    else:
        out, env = tmp_path / "view.mp4", {"PATH": str(tmp_path)}
    r = runner.invoke(app, ["view", str(src), "--out", str(out)], env=env)
    assert r.exit_code == 2, r.output
    assert "Traceback" not in r.output and re.search(message, " ".join(r.output.split()))
    assert r.output.startswith("error:") and not out.exists()


@pytest.mark.parametrize("kind", ["so3", "ball"])
def test_gif_has_the_frames(tmp_path: Path, kind: str) -> None:
    Image = pytest.importorskip("PIL.Image", reason="Pillow is not installed")
    out = og.view(BODIES[kind](), tmp_path / "slew.gif", frames=3)
    im = Image.open(out)
    assert im.n_frames == 3 and im.size == (480, 400)
    pictures = []
    for k in range(3):
        im.seek(k)
        pictures.append(np.asarray(im.convert("L")))
    assert not np.array_equal(pictures[0], pictures[2]), "the body did not move"
    assert (pictures[0] < 200).mean() > 0.01, "the frame is blank"


def test_mp4(tmp_path: Path) -> None:
    if shutil.which("ffmpeg") is None:
        with pytest.raises(DependencyError, match="needs ffmpeg on PATH"):
            og.view(so3(), tmp_path / "slew.mp4", frames=3)
        pytest.skip("ffmpeg is not on PATH: the MP4 writer is not installed")
    out = og.view(so3(), tmp_path / "slew.mp4", frames=3)
    assert out.stat().st_size > 1000


# -- a real browser -----------------------------------------------------------------------

@pytest.fixture(scope="module")
def browser() -> Any:
    binary = find_chromium()
    if binary is None:
        pytest.skip("no Chromium found (/usr/bin/chromium, chromium-browser, google-chrome): "
                    "install it (apt-get install chromium) to test the page in a browser")
    with Browser(binary) as b:
        yield b


def picture(png: bytes) -> np.ndarray:
    """The canvas part of a screenshot (below the title and legend, above the controls), grey."""
    from PIL import Image

    im = np.asarray(Image.open(io.BytesIO(png)).convert("L"))
    assert im.shape == (700, 900)
    return im[110:640]


@pytest.mark.parametrize("kind", BODIES)
def test_page_plays_in_a_browser(browser: Browser, tmp_path: Path, kind: str) -> None:
    """Loaded offline at two times (#t= and ?t=): no errors, a drawing, and the two differ."""
    path = og.view(BODIES[kind](), tmp_path / "view.html")
    early = browser.open(path.as_uri() + "#t=0.3")
    late = browser.open(path.as_uri() + "?t=1.7")
    assert early.errors == [] and late.errors == []
    a, b = picture(early.png), picture(late.png)
    for im in (a, b):
        assert (im < 200).mean() > 0.01, "the drawing is blank"
    assert (np.abs(a.astype(int) - b.astype(int)) > 40).sum() > 300, "the body did not move"


def test_browser_test_catches_a_broken_page(browser: Browser, tmp_path: Path) -> None:
    """The same page with a script error, and one loading a script from the network: both
    are caught (the check above would fail on them)."""
    good = page(scene(so3(), 20))
    broken = tmp_path / "broken.html"
    broken.write_text(good.replace("const canvas =", "const canvas = undefinedName ||"))
    found = browser.open(broken.as_uri()).errors
    assert any("undefinedName" in e for e in found), found
    online = tmp_path / "online.html"
    online.write_text(good.replace("<title>", '<script src="http://127.0.0.1:9/x.js"></script>'
                                   "<title>"))
    assert browser.open(online.as_uri()).errors, "a failed load went unnoticed"
