"""The scenario atlas of ``benchmarks/scenarios.py``: the docs/physics.md §5 observations run on
one joint, each scenario measured against its criterion (``outcome``), the self-weight runs they
share (``self_weight``), the installed state of an installation run (``installed``), the branches
run from a saved state (``stepping``: the dismount runs of ``dismount``, the load-direction runs
of ``direction``), the scenarios themselves (``catalogue``) and the page that collects them
(``page``)."""
