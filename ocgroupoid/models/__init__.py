"""The canonical systems, written with the public API only.

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
