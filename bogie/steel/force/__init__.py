"""Stage 4's compiled model: the internal force of the nonlinear model and what it is built from (numba).

- :mod:`.core`: the internal force, split by physics into inlined helpers (the springs and their end-friction return
  map, pad moments, tyres, bushes, stops, the record);
- :mod:`.layout`: **the one definition of the packed layout** (``SCALARS``, ``ARRAYS``, ``RECORD``, ``WORK``);
- :mod:`.geometry`: body points, radius rods and rolling contact points;
- :mod:`.pack`: a :class:`~bogie.params.Bogie` packed for the force, the cache of its constants, the freedoms' limits;
- :mod:`.equilibrium`: **the one Newton iteration** of the static equilibrium.

A room of its own, below its users (:mod:`bogie.steel.nonlinear`, the integrator :mod:`bogie.steel.newmark`, the
phases :mod:`bogie.steel.phases`), and deliberately light: importing one of these modules runs this file first, so it
imports nothing (a heavy package here would put the integrator and Stage 4's Python layer in a circle).
"""
