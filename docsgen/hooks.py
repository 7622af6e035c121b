"""The MkDocs hook (``hooks:`` in mkdocs.yml): fills every ``<!-- generated: NAME -->``
marker of a page with the Markdown its generator writes, at build time, and shows the Sphinx
roles of the docstrings (``:meth:`solve```) as code."""

from __future__ import annotations

import re
import sys
from pathlib import Path
from typing import Any, Callable

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))  # mkdocs loads this by path

from docsgen import bench, cli, schema  # noqa: E402

MARKER = re.compile(r"^<!-- generated: ([\w-]+) -->$", re.MULTILINE)
#: a Sphinx role of a docstring as mkdocstrings renders it, ``:meth:<code>~x.y</code>``
ROLE = re.compile(r":(?:meth|func|class|data|mod|attr|exc|obj):(<code>)~?")
GENERATORS: dict[str, Callable[[], str]] = {"problem-file-reference": schema.markdown,
                                            "cli-reference": cli.markdown, **bench.RENDERERS}


def fill(markdown: str, where: str = "") -> str:
    """``markdown`` with its markers replaced; an unknown marker is an error."""
    def replace(m: re.Match[str]) -> str:
        if m.group(1) not in GENERATORS:
            raise ValueError(f"{where}: no generator {m.group(1)!r}; known: "
                             + ", ".join(GENERATORS))
        return GENERATORS[m.group(1)]()
    return MARKER.sub(replace, markdown)


def on_page_markdown(markdown: str, page: Any, **kwargs: Any) -> str:
    """MkDocs event: the page's Markdown before it is rendered."""
    return fill(markdown, page.file.src_path)


def on_page_content(html: str, **kwargs: Any) -> str:
    """MkDocs event: the page's HTML; the docstrings' Sphinx roles shown as plain code."""
    return ROLE.sub(r"\1", html)
