"""One version source: ``ocgroupoid/_version.py``, which the package metadata reads."""

from __future__ import annotations

import importlib.metadata
import re
from pathlib import Path

import pytest

import ocgroupoid

ROOT = Path(__file__).resolve().parent.parent


def test_version_is_the_installed_metadata() -> None:
    try:
        installed = importlib.metadata.version("ocgroupoid")
    except importlib.metadata.PackageNotFoundError:
        pytest.skip("ocgroupoid is imported from the source tree, not installed")
    assert ocgroupoid.__version__ == installed


def test_pyproject_reads_the_version_from_the_package() -> None:
    tomllib = pytest.importorskip("tomllib")  # Python >= 3.11
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())
    assert "version" not in project["project"], "the version is written in _version.py only"
    assert "version" in project["project"]["dynamic"]
    attr = project["tool"]["setuptools"]["dynamic"]["version"]["attr"]
    assert attr == "ocgroupoid._version.__version__"
    assert re.fullmatch(r"\d+\.\d+\.\d+(\S*)", ocgroupoid.__version__), ocgroupoid.__version__
