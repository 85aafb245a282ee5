"""bogie: why mechanically equalised multi-axle trailer bogies do not share load equally.

Modules: :mod:`bogie.params` (the bogie and its presets), :mod:`bogie.static` (Stage 2, Equation 1),
:mod:`bogie.metrics` (p, P1, RMS, LSC, DLC, road-wear factor), :mod:`bogie.plotting` (figures).
"""

from bogie.params import INHIBITORS, Bogie, preset, tandem_trrl, triaxle_stage1

__all__ = ["INHIBITORS", "Bogie", "preset", "tandem_trrl", "triaxle_stage1"]
__version__ = "0.1.0"
