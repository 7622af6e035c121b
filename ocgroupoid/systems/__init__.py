"""The canonical systems, written with the public API only.

``models`` (plural) holds the *models* — rigid body, heavy top, plate-ball, quadrotor... —
each a function building a :class:`~ocgroupoid.model.problem.Problem`, registered under the
name a problem file's ``model:`` key selects. The language they are written in (Problem,
mechanics, boundary values, labels) is :mod:`ocgroupoid.model` (singular), below them.

Every module in this package is imported here; each registers its model spec, so a new
model is one new file.
"""

from __future__ import annotations

import importlib
import pkgutil

from .registry import MODELS, ModelSpec, register

for _info in pkgutil.iter_modules(__path__):
    if _info.name != "registry":
        importlib.import_module(f"{__name__}.{_info.name}")

__all__ = ["MODELS", "ModelSpec", "register"]
