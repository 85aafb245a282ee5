"""Sampling a fleet: what varies between the bogies and how, drawn from one seeded design.

- :mod:`.sample`: :class:`Fleet`, :func:`sample_fleet`, :func:`design_bogie`, :func:`bogie_from_sample`, the sample
  ``COLUMNS`` (this package's code before issue 42 made it a folder);
- :mod:`.distributions`: the quantities' distributions and their inverse CDFs;
- :mod:`.sensitivity`: :func:`sensitivity_design`, the Sobol' sensitivity design (SALib's Saltelli sampling) of
  chosen factors around one axle group's base bogie, and :func:`sensitivity_problem`, its SALib problem;
- :mod:`.seeds`: every stream of the master seed (the road, the sensor, a suspension's draw, a design's);
- :mod:`.tilted`: the effective payload fraction of a tilted trailer.

Names load on first use (:mod:`bogie.lazy`).
"""

from bogie.lazy import lazy_names

#: each public name of the room -> the module that defines it (bogie.fleet re-exports them all)
EXPORTS: dict[str, str] = {
    **dict.fromkeys(("COLUMNS", "FLEET_QUANTITIES", "SAMPLING_SETTINGS", "Fleet", "FleetError", "bogie_from_sample",
                     "design_bogie", "sample_fleet"), "sample"),
    **dict.fromkeys(("SENSITIVITY_FACTORS", "sensitivity_design", "sensitivity_problem"), "sensitivity"),
    **dict.fromkeys(("design_seed", "road_seed", "sensor_seed", "suspension_draw"), "seeds"),
    **dict.fromkeys(("Choice", "Constant", "Distribution", "LogNormal", "LogUniform", "Normal", "ParameterError",
                     "TruncNormal", "Uniform"), "distributions"),
}  # fmt: skip
__getattr__, __dir__ = lazy_names(__name__, EXPORTS, former="sample")
