"""The scenario atlas of ``benchmarks/scenarios.py``: the docs/physics.md §5 observations run on
one joint, each scenario measured against its criterion (``outcome``), the self-weight runs they
share (``self_weight``), the scenarios themselves (``catalogue``) and the page that collects them
(``page``)."""
