"""Weighing a fleet: each bogie on a static weighbridge and by a weigh-in-motion pass, one run row each, and the
survey of the runs.

- :mod:`.settings`: :class:`StaticProtocol`, :class:`WimProtocol`, their settings declared with :mod:`bogie.settings`;
- :mod:`.protocols`: how one bogie is weighed (the static weighbridge, the WIM pass over its site and sensor; a steel
  group as :mod:`bogie.steel.phases`, an air-sprung one through :mod:`bogie.air.dynamics`);
- :mod:`.weigher`: :func:`weigh_fleet` over any executor, :func:`weigh_rows`, a chunk's result columns (this package's
  code before issue 42 made it a folder);
- :mod:`.runs`: the runs table's columns, dtypes, units, categories and null rule;
- :mod:`.survey`: :func:`survey_tables`, the roadside-survey statistics of a runs table;
- :mod:`.observed`: :func:`simulated_readings` and :func:`compare`, the runs through an observed survey's filters.

Names load on first use (:mod:`bogie.lazy`).
"""

from bogie.lazy import lazy_names

#: each public name of the room -> the module that defines it (bogie.fleet re-exports them all)
EXPORTS: dict[str, str] = {
    **dict.fromkeys(("StaticProtocol", "WimProtocol"), "settings"),
    **dict.fromkeys(("weigh", "weigh_fleet", "weigh_rows"), "weigher"),
    "survey_tables": "survey",
    **dict.fromkeys(("compare", "simulated_readings"), "observed"),
}
__getattr__, __dir__ = lazy_names(__name__, EXPORTS, former="weigher")
