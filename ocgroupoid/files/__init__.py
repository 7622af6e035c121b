"""Problem files: YAML read safely, validated with messages that name the key, the line and
the fix, and built into a Problem (built-in models or ``model: custom``), a method and solver
options."""

from .load import Config, build, estimate, fixed_grid, load
from .solving import build_all, method, options

__all__ = ["Config", "load", "build", "estimate", "fixed_grid", "method", "options",
           "build_all"]
