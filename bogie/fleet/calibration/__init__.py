"""Calibration to an observed survey (``docs/calibration.md``): the fleet quantities fitted to a survey's readings.

- :mod:`.settings`: :class:`CalibrationSettings`, :class:`CalibrationError`, ``check_fit`` (what params.yaml's loader
  reads, light on purpose);
- :mod:`.problem`: the observed groups, the energy distance, the problem (this package's code before issue 42 made
  it a folder);
- :mod:`.table`: the calibration fleet, its common random numbers and its table of readings over any executor;
- :mod:`.priors`, :mod:`.posterior`, :mod:`.fitting`: the priors, the synthetic-likelihood posterior, differential
  evolution and the bootstrap (:func:`calibrate`);
- :mod:`.site`: the WIM site in the observation model, its road shared by a survey's vehicles at their own speeds
  (:class:`Site`); its bias and the covariance between sites are :mod:`.table`'s and :mod:`.posterior`'s;
- :mod:`.convergence`: whether the posterior's chains converged (R-hat, bulk and tail ESS) and what to change;
- :mod:`.prior_sensitivity`: the posterior again with the tilt's prior sd halved and doubled;
- :mod:`.attribution`: what each cause explains;
- :mod:`.checks`: the calibrated fleet simulated directly, the posterior predictive, the held-out half, the ablation,
  :func:`calibrate_survey`;
- :mod:`.synthetic`: :func:`write_csv_survey`, simulated groups as a survey file.

Names load on first use (:mod:`bogie.lazy`).
"""

from bogie.lazy import lazy_names

#: each public name of the room -> the module that defines it (bogie.fleet re-exports them all)
EXPORTS: dict[str, str] = {
    **dict.fromkeys(("CalibrationError", "CalibrationSettings"), "settings"),
    **dict.fromkeys(("Observed", "make_problem", "observed_groups"), "problem"),
    **dict.fromkeys(("Table", "base_values", "build_table"), "table"),
    "calibrate": "fitting",
    **dict.fromkeys(("calibrate_survey", "simulate_fleet"), "checks"),
    "write_csv_survey": "synthetic",
    "Site": "site",
}
__getattr__, __dir__ = lazy_names(__name__, EXPORTS, former="problem")
