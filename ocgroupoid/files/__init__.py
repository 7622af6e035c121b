"""Problem files: YAML read safely, validated with messages that name the key, the line and
the fix, and built into a Problem (built-in models or ``model: custom``)."""

from .load import Config, build, estimate, fixed_grid, load

__all__ = ["Config", "load", "build", "estimate", "fixed_grid"]
