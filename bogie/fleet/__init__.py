"""Fleet studies from Python, without a params file: sample a fleet, weigh it, survey it, compare it with a survey.

The steps of the project's pipeline as plain functions (``docs/tutorial.md`` runs them end to end):

- :class:`Fleet` and :func:`sample_fleet`: what varies between the bogies and how (one distribution per quantity,
  :mod:`bogie.fleet.distributions`), drawn from one seeded Latin hypercube or Sobol' design (:mod:`.sampling`);
- :class:`StaticProtocol`, :class:`WimProtocol` and :func:`weigh_fleet`: each bogie weighed on a static weighbridge
  and by a weigh-in-motion pass over a random ISO 8608 road, one run row each, a failure a row with its reason
  (:mod:`.protocols`, :mod:`.weighing`, :mod:`.runs`);
- :func:`survey_tables`: the roadside-survey statistics of the runs (:mod:`.survey`);
- :class:`DesignSettings` and :func:`study_designs`: the design guidance's controlled experiment, every design over
  the same operating conditions, its shares within 5 %, tilt tolerances and Pareto fronts (:mod:`.design`,
  :mod:`.design_analysis`; ``docs/design.md``);
- :func:`compare`: the runs' readings and an observed survey (:func:`bogie.weighings.survey.observed_survey`)
  through the one definition of the survey statistics (:mod:`.observed`).
- :func:`calibrate_survey`: the fleet quantities (tilt, air share, WIM site roughness, sensor error) fitted to an
  observed survey on a table of readings (:func:`build_table`), with its intervals and checks (:mod:`.calibration`,
  :mod:`.calibration_checks`, ``docs/calibration.md``).

Every quantity is SI unless its name says otherwise (``_kg``, ``_t``, ``_deg``, ``_pct``). Same arguments and seed,
same table: whatever the executor, the number of workers or the CPU.

The names below are loaded on first use (PEP 562), so that a module importing one submodule (the simulate stage
imports :mod:`.weighing`) neither loads nor depends on the others: the pipeline's code dependencies and the
simulate stage's code hash follow imports (:mod:`pipeline.deps`).
"""

from __future__ import annotations

import importlib
from typing import Any

#: each public name -> the submodule that defines it
_EXPORTS: dict[str, str] = {
    **dict.fromkeys(
        ("DesignExperiment", "DesignStudy", "design_experiment", "study_designs", "weigh_designs"), "design"
    ),
    **dict.fromkeys(("DesignError", "DesignSettings"), "design_settings"),
    **dict.fromkeys(("DesignAnalysis", "analyse_designs", "guidance_sentences", "tilt_tolerance"), "design_analysis"),
    **dict.fromkeys(
        ("Choice", "Constant", "Distribution", "LogNormal", "LogUniform", "Normal", "ParameterError", "TruncNormal",
         "Uniform"),
        "distributions",
    ),
    **dict.fromkeys(
        ("Observed", "Table", "base_values", "build_table", "make_problem", "observed_groups"), "calibration"
    ),
    **dict.fromkeys(("CalibrationError", "CalibrationSettings"), "calibration_settings"),
    "calibrate": "calibration_fit",
    **dict.fromkeys(("calibrate_survey", "simulate_fleet", "write_csv_survey"), "calibration_checks"),
    **dict.fromkeys(("compare", "simulated_readings"), "observed"),
    **dict.fromkeys(("StaticProtocol", "WimProtocol"), "protocol_settings"),
    **dict.fromkeys(
        ("FLEET_QUANTITIES", "Fleet", "FleetError", "bogie_from_sample", "design_bogie", "sample_fleet"), "sampling"
    ),
    "survey_tables": "survey",
    **dict.fromkeys(("weigh", "weigh_fleet"), "weighing"),
}  # fmt: skip
#: a public name defined outside the package: the observed survey of a file (bogie.weighings.survey)
_OUTSIDE = {"observed_survey": "bogie.weighings.survey"}

__all__ = sorted([*_EXPORTS, *_OUTSIDE])


def __getattr__(name: str) -> Any:
    if name in _EXPORTS:
        module = importlib.import_module(f"{__name__}.{_EXPORTS[name]}")
    elif name in _OUTSIDE:
        module = importlib.import_module(_OUTSIDE[name])
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(module, name)
    globals()[name] = value  # the next lookup is a plain one
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})
