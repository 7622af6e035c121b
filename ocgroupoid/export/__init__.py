"""Exported C code: the compiled problem's Functions emitted with a small C library."""

from .codegen import (
    DEFAULT_PREFIX,
    Export,
    claim_folder,
    export_c,
    make,
    positive_parameters,
    write_params,
)

__all__ = ["DEFAULT_PREFIX", "Export", "claim_folder", "export_c", "make",
           "positive_parameters", "write_params"]
