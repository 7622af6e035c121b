"""Exported C code: the compiled problem's Functions emitted with a small C library."""

from .codegen import Export, export_c, make, write_params

__all__ = ["Export", "export_c", "make", "write_params"]
