"""How a pavement design guide counts an axle group's damage: AASHTO 1993's load equivalence factors of single, tandem
and tridem loads, and Austroads' standard loads per axle group (derivation and sources: ``docs/pavement.md``,
"What the design guides count").

**AASHTO 1993, flexible pavements** (Guide for Design of Pavement Structures, Appendix D; the equation as the guide's
worked examples use it, Pavement Interactive, "Flexible Pavement ESAL Equation"): the load equivalence factor of a
group of ``L_2`` axles (1 single, 2 tandem, 3 tridem) carrying ``L_x`` kips in all, against the 18-kip single axle,
is ``LEF = W_t18 / W_tx`` with

    log10(W_tx / W_t18) = 4.79 log10(18 + 1) - 4.79 log10(L_x + L_2) + 4.33 log10(L_2) + G_t / beta_x - G_t / beta_18,
    G_t = log10((4.2 - p_t) / (4.2 - 1.5)),
    beta_x = 0.40 + 0.081 (L_x + L_2)^3.23 / ((SN + 1)^5.19 L_2^3.23),   beta_18 = beta_x at L_x = 18, L_2 = 1,

``SN`` the structural number and ``p_t`` the terminal serviceability. It reproduces the guide's tables: a 40-kip
tandem on SN 5 at p_t 2.5 is 2.08 (Table D.5), a 30-kip single axle on SN 3 at p_t 2.5 is 7.9 (Table D.4). The
guide's factor is of the group's total load: **how the group shares it between its axles is not in it**.

**Austroads' standard loads** per group (Guide to Pavement Technology Part 2, AGPT02, chapter 7, design traffic; as
tabulated from Austroads 2006 by weighinmotion.net, "Vehicle mass"): single axle with dual tyres 80 kN, tandem with
dual tyres 135 kN, tri-axle with dual tyres 181 kN. A group of load ``W`` does ``(W / W_group)^m`` standard axle
repetitions at damage exponent ``m``; again the group's total alone.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from bogie import numerics
from bogie.params import GRAVITY
from bogie.settings import check_value

__all__ = [
    "AUSTROADS_GROUP_LOAD_KN",
    "GROUP_AXLES",
    "KIPS_PER_KG",
    "aashto_flexible_lef",
]

#: Austroads' standard load of each axle group with dual tyres, AGPT02 chapter 7 (Austroads 2006 as tabulated by
#: weighinmotion.net; the table's number in the guide not read): single 80, tandem 135, tri-axle 181 kN [kN]
AUSTROADS_GROUP_LOAD_KN: dict[str, float] = {"single": 80.0, "tandem": 135.0, "triaxle": 181.0}
#: axles of each group, AASHTO's L_2 [-]
GROUP_AXLES: dict[str, int] = {"single": 1, "tandem": 2, "triaxle": 3}
#: a kilogram's weight in kips at the project's g (:data:`bogie.params.GRAVITY`; 1 lbf = 4.4482216152605 N) [kip/kg]
KIPS_PER_KG: float = GRAVITY / 4448.2216152605


def _beta(load_kips: NDArray[np.float64], axles: int, structural_number: float) -> NDArray[np.float64]:
    return 0.40 + 0.081 * numerics.power(load_kips + axles, 3.23) / (
        math.pow(structural_number + 1.0, 5.19) * math.pow(axles, 3.23)
    )


def aashto_flexible_lef(
    load_kips: ArrayLike, axles: int, structural_number: float = 5.0, terminal_serviceability: float = 2.5
) -> NDArray[np.float64]:
    """AASHTO 1993's load equivalence factor of a group of ``axles`` (1, 2 or 3) carrying ``load_kips`` in all, on a
    flexible pavement of ``structural_number`` at ``terminal_serviceability`` (the module docstring's equation) [-].

    Raises
    ------
    ValueError
        naming the argument, its value, the allowed range and the unit, for ``axles`` not 1, 2 or 3, a structural
        number outside (0, 12] (AASHTO's design chart reads 1-6), a terminal serviceability outside [1.5, 4.2) or a
        load not positive and finite.
    """
    if axles not in (1, 2, 3) or isinstance(axles, bool):
        raise ValueError(f"axles = {axles!r}: must be 1 (single), 2 (tandem) or 3 (tridem), AASHTO's L_2 [-]")
    check_value("structural_number", structural_number, "-", low=0.0, high=12.0, low_open=True)
    check_value("terminal_serviceability", terminal_serviceability, "-", low=1.5, high=4.2, high_open=True)
    load = np.asarray(load_kips, dtype=float)
    if not np.all(np.isfinite(load)) or np.any(load <= 0.0):
        raise ValueError(f"load_kips = {load_kips!r}: must be positive and finite [kip]")
    g = math.log10((4.2 - terminal_serviceability) / (4.2 - 1.5))
    log_ratio = (
        4.79 * math.log10(19.0) - 4.79 * numerics.log(load + axles) / math.log(10.0) + 4.33 * math.log10(axles)
        + g / _beta(load, axles, structural_number) - g / _beta(np.asarray(18.0), 1, structural_number)
    )  # fmt: skip
    return numerics.power(10.0, -log_ratio)
