"""Generators of the documentation site's reference and benchmark pages.

Not part of the installed package: ``mkdocs build`` runs :mod:`docsgen.hooks`, which fills
the ``<!-- generated: NAME -->`` markers of the pages from the pydantic models of the problem
files (:mod:`docsgen.schema`), the command line's click commands (:mod:`docsgen.cli`) and the
benchmark summaries kept in ``docs/benchmarks/data`` (:mod:`docsgen.bench`, written from
``results/`` by :mod:`docsgen.extract`).
"""
