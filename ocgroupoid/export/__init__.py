"""Exported C code: the compiled problem's Functions emitted with a small C library."""

from ..model.ranges import positive_parameters
from .codegen import Export, claim_folder, export_c, make, write_params

__all__ = ["Export", "claim_folder", "export_c", "make", "positive_parameters", "write_params"]
