"""What solves the model: kinematics, inverse dynamics, forward dynamics, and the study's own formulation.

* :mod:`~vibkit.analyses.kinematics`, :mod:`~vibkit.analyses.inverse`, :mod:`~vibkit.analyses.forward`:
  the three analyses;
* :mod:`~vibkit.analyses.integrate`: dopri5 with breakpoints, and the other integrators;
* :mod:`~vibkit.analyses.simulation`: :func:`simulate`, one scene to one :class:`xarray.Dataset`;
* :mod:`~vibkit.analyses.results`: the Dataset's layout, units and provenance;
* :mod:`~vibkit.analyses.reference`: the study's formulation, a baseline for benchmarks and tests.
"""
