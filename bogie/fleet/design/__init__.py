"""The design guidance's controlled experiment (``docs/design.md``): every design over the same operating conditions.

- :mod:`.settings`: :class:`DesignSettings` and :class:`DesignError` (what params.yaml's loader reads, light on
  purpose);
- :mod:`.experiment`: the designs, the operating conditions, the tilt grid and sample rows, :func:`design_experiment`,
  :func:`weigh_designs` over any executor, :func:`study_designs` end to end (this package's code before issue 42 made
  it a folder), :func:`weigh_own_design` (a designer's bogie file and today's typical design alone, in seconds);
- :mod:`.analysis`: :func:`analyse_designs`, the shares within 5 % with Wilson intervals, :func:`tilt_tolerance`,
  Pareto fronts, :func:`guidance_sentences`;
- :mod:`.table`: the roadside survey's design-guidance table.

Names load on first use (:mod:`bogie.lazy`).
"""

from bogie.lazy import lazy_names

#: each public name of the room -> the module that defines it (bogie.fleet re-exports them all)
EXPORTS: dict[str, str] = {
    **dict.fromkeys(("DesignError", "DesignSettings"), "settings"),
    **dict.fromkeys(("DesignExperiment", "DesignStudy", "design_experiment", "study_designs", "weigh_designs",
                     "weigh_own_design"), "experiment"),
    **dict.fromkeys(("DesignAnalysis", "analyse_designs", "guidance_sentences", "tilt_tolerance"), "analysis"),
}  # fmt: skip
__getattr__, __dir__ = lazy_names(__name__, EXPORTS, former="experiment")
