"""Fleet studies from Python, without a params file: sample a fleet, weigh it, survey it, compare it with a survey.

The steps of the project's pipeline as plain functions (``docs/tutorial.md`` runs them end to end), in rooms by
concern:

- :mod:`.sampling`: :class:`Fleet` and :func:`sample_fleet`, what varies between the bogies and how (one
  distribution per quantity, :mod:`.sampling.distributions`), drawn from one seeded Latin hypercube or Sobol' design;
  :func:`sensitivity_design`, the Sobol' sensitivity design (SALib's Saltelli sampling) of chosen quantities;
- :mod:`.weighing`: :class:`StaticProtocol`, :class:`WimProtocol` and :func:`weigh_fleet`, each bogie weighed on a
  static weighbridge and by a weigh-in-motion pass over a random ISO 8608 road, one run row each, a failure a row
  with its reason; :func:`survey_tables`, the roadside-survey statistics of the runs; :func:`compare`, the runs'
  readings and an observed survey (:func:`bogie.weighings.survey.observed_survey`) through the one definition of the
  survey statistics;
- :mod:`.design`: :class:`DesignSettings` and :func:`study_designs`, the design guidance's controlled experiment,
  every design over the same operating conditions, its shares within 5 %, tilt tolerances and Pareto fronts
  (``docs/design.md``);
- :mod:`.calibration`: :func:`calibrate_survey`, the fleet quantities (tilt, air share, WIM site roughness, sensor
  error) fitted to an observed survey on a table of readings (:func:`build_table`), with its intervals and checks
  (``docs/calibration.md``);
- :mod:`.road`: what unequal sharing costs the road (``docs/pavement.md``); :mod:`.constants`: what they share.

Every quantity is SI unless its name says otherwise (``_kg``, ``_t``, ``_deg``, ``_pct``). Same arguments and seed,
same table: whatever the executor, the number of workers or the CPU.

The names below, and each room's, are loaded on first use (:mod:`bogie.lazy`), so that a module importing one
submodule (the simulate stage imports :mod:`.weighing.weigher`) neither loads nor depends on the others: the
pipeline's code dependencies and the simulate stage's code hash follow imports (:mod:`pipeline.deps`).
"""

from __future__ import annotations

import importlib

from bogie.lazy import lazy_names

#: the rooms, each declaring its public names once (its EXPORTS); importing one runs only its light __init__.py
_ROOMS = ("sampling", "weighing", "design", "calibration")
#: each public name -> the submodule that defines it: every room's names, and the observed survey of a file
_EXPORTS: dict[str, str] = {
    name: f"{room}.{module}"
    for room in _ROOMS
    for name, module in importlib.import_module(f"{__name__}.{room}").EXPORTS.items()
}
_EXPORTS["observed_survey"] = "bogie.weighings.survey"

__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_names(__name__, _EXPORTS)
