"""Benchmarks of the schemes against RK4 shooting baselines (``ocgroupoid bench``).

:func:`~ocgroupoid.bench.workprecision.work_precision` times every method on a geometric
range of N against a reference cost (:mod:`~ocgroupoid.bench.reference`) and the replay's
landing error, and draws the work-precision chart (:mod:`~ocgroupoid.bench.chart`);
:func:`~ocgroupoid.bench.stability.stability` maps where each method fails over slew angles
and grids (:mod:`~ocgroupoid.bench.outcome`, :mod:`~ocgroupoid.bench.stability_chart`). Both
write a JSON line per solve as they go (:mod:`~ocgroupoid.bench.record`), then a summary JSON
and a PNG.

The scripts of ``scripts/`` are built on the same modules: their command line and progress
bar (:mod:`~ocgroupoid.bench.script`), medians (:mod:`~ocgroupoid.bench.timing`), summaries
with the machine (:mod:`~ocgroupoid.bench.record`), observed orders
(:mod:`~ocgroupoid.verify.richardson`); ``scripts/bench_schemes.py`` runs the work-precision
of every problem file.

Nothing is imported here: the command line (:mod:`~ocgroupoid.bench.commands`) registers
the ``bench`` group without loading the solvers, SciPy or matplotlib.
"""
