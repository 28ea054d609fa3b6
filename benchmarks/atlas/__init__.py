"""The scenario atlas of ``benchmarks/scenarios.py``: the docs/physics.md §5 observations run on
the default joint, each scenario measured against its criterion (``outcome``), the joint settled
by its self-weight stage with the installation run's frequency choice (``settled``), the
self-weight runs the scenarios share (``self_weight``), the installed state of an installation
run (``installed``), the branches run from a saved state (``stepping``: the dismount runs of
``dismount``, the load-direction runs of ``direction``), the scenarios themselves,
one module each (``criteria``), where they run (``context``), their list (``catalogue``) and
the page that collects them (``page``)."""
