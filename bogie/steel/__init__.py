"""The steel-equalised bogie's model: the reference's stages as rooms, each compiled kernel beside its user.

- :mod:`bogie.steel.fe`: Stage 1, the finite element model of Figure 2, on the generic frame solver
  :mod:`bogie.steel.fe.frame`;
- :mod:`bogie.steel.static`: Stage 2, Equation 1 generalised to n axles, and the static loads at a chassis tilt;
- :mod:`bogie.steel.linear`: Stage 3, the linear dynamic model;
- :mod:`bogie.steel.nonlinear`: Stage 4, the nonlinear model (the four inhibitors, the spring hysteresis): its inputs
  and simulation;
- :mod:`bogie.steel.force`: Stage 4's compiled model: the internal force (:mod:`.force.core`), its packed layout,
  geometry and pack, and the one static equilibrium (:mod:`.force.equilibrium`);
- :mod:`bogie.steel.newmark`: the time integrator (Newmark, generalised-alpha) with its compiled loops
  (:mod:`.newmark.kernels`);
- :mod:`bogie.steel.phases`: a weighing as phases of the Stage 4 model in one compiled call, its kernel in private
  modules beside it;
- :mod:`bogie.steel.cases`: the reference's named runs (Tables 1 and 2).

What the bogie is (:mod:`bogie.params`, :mod:`bogie.presets`, :mod:`bogie.bogie_file`) and what every model shares
(:mod:`bogie.metrics`, :mod:`bogie.results`, :mod:`bogie.numerics`, :mod:`bogie.lu`) stay at the top of the package:
the air-sprung groups (:mod:`bogie.air`) use them too. The modules' old paths (``bogie.static``, ``bogie.nonlinear``,
...) work for one release with a DeprecationWarning (:mod:`bogie._moved`).
"""
