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
import os
from collections.abc import Mapping
from functools import partial
from pathlib import Path

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike, NDArray

from bogie import numerics
from bogie.group_names import GROUP_AXLES
from bogie.params import GRAVITY
from bogie.settings import check_value

__all__ = [
    "AUSTROADS_GROUP_LOAD_KN",
    "KIPS_PER_KG",
    "STANDARD_AXLE_KN",
    "SHARING_FACTORS_HEADER",
    "aashto_flexible_lef",
    "aashto_view",
    "group_baseline_factor",
    "sharing_factors",
    "with_group_baseline",
    "write_sharing_factors",
]

#: Austroads' standard load of each axle group with dual tyres, AGPT02 chapter 7 (Austroads 2006 as tabulated by
#: weighinmotion.net; the table's number in the guide not read): single 80, tandem 135, tri-axle 181 kN [kN]
AUSTROADS_GROUP_LOAD_KN: dict[str, float] = {"single": 80.0, "tandem": 135.0, "triaxle": 181.0}
#: the standard single axle with dual tyres, AASHO's 18 kips and Austroads' 80 kN [kN]
STANDARD_AXLE_KN: float = 80.0
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


def aashto_view(
    loads_kg: ArrayLike, structural_number: float = 5.0, terminal_serviceability: float = 2.5
) -> dict[str, NDArray[np.float64]]:
    """What AASHTO 1993 says about groups of axle loads ``loads_kg`` (groups, axles: 2 or 3 columns, every one
    loaded) [kg], on a flexible pavement (:func:`aashto_flexible_lef`'s ``structural_number`` and
    ``terminal_serviceability``):
    ``group``, each group's factor as the guide counts it (a tandem's or tridem's total load: its sharing not in it);
    ``single_axles``, the sum of its axles' factors as single axles, as they share the load; ``single_axles_equal``,
    the same with the load shared equally [-]. The last two differ only by the sharing; the first is what a design
    built on the guide counts (docs/pavement.md, "What the design guides count")."""
    w = np.atleast_2d(np.asarray(loads_kg, dtype=float))
    if w.shape[1] not in (2, 3) or not np.all(np.isfinite(w)) or np.any(w <= 0.0):
        raise ValueError(f"loads_kg of shape {w.shape}: must be groups of 2 or 3 positive, finite axle loads [kg]")
    kips = w * KIPS_PER_KG
    n = w.shape[1]
    lef = partial(aashto_flexible_lef, structural_number=structural_number,
                  terminal_serviceability=terminal_serviceability)  # fmt: skip
    mean = kips.sum(axis=1) / n
    return {
        "group": lef(kips.sum(axis=1), n),
        "single_axles": sum(lef(kips[:, i], 1) for i in range(n)),
        "single_axles_equal": n * lef(mean, 1),
    }


def group_baseline_factor(size: str, k: float) -> float:
    """What the per-axle equal-sharing damage of a group of ``size`` (``tandem``, ``triaxle``) is in Austroads'
    group standard axle repetitions at exponent ``k``, whatever its load ``W`` [-]:

        D_eq / D_group = n (W / n / W_s)^k / (W / W_group)^k = n^(1 - k) (W_group / W_s)^k,

    ``W_s`` 80 kN, ``W_group`` :data:`AUSTROADS_GROUP_LOAD_KN`. 1.014 (tandem) and 0.971 (tri-axle) at k = 4, 0.26
    and 0.10 at k = 12 (``docs/pavement.md``). NaN for a size with no group standard load."""
    if size not in GROUP_AXLES:
        return math.nan
    n = GROUP_AXLES[size]
    return math.pow(n, 1.0 - k) * math.pow(AUSTROADS_GROUP_LOAD_KN[size] / STANDARD_AXLE_KN, k)


def with_group_baseline(frame: pd.DataFrame, exponents: Mapping[str, float]) -> pd.DataFrame:
    """``frame`` (:func:`bogie.weighings.wear.wear_statistics`' table, with a ``group`` column) with the extra wear
    against Austroads' group baseline: per exponent name ``<k>``, ``extra_wear_group_<k>`` (and ``_low``, ``_high``)
    = ``extra_wear_<k>`` x :func:`group_baseline_factor` of the row's group: the extra damage of unequal sharing as a
    share of what the guide counts for the same groups [-]. Exact for a cell of one size (D - D_eq and D_eq both sum
    over its groups and D_group = D_eq / the factor for every one of them); NaN for a size with no group load or
    without a ``group`` column."""
    out = frame.copy()
    sizes = out["group"] if "group" in out.columns else pd.Series([None] * len(out), index=out.index)
    for name, k in exponents.items():
        factor = np.array([group_baseline_factor(str(g), float(k)) for g in sizes], dtype=float)
        for tail in ("", "_low", "_high"):
            column = f"extra_wear_{name}{tail}"
            values = out[column].to_numpy(dtype=float) if column in out.columns else np.full(len(out), math.nan)
            out[f"extra_wear_group_{name}{tail}"] = values * factor
    return out


#: the words at the head of a sharing-factors file (:func:`write_sharing_factors`), each line written after "# "
SHARING_FACTORS_HEADER: tuple[str, ...] = (
    "Sharing factors of axle groups for pavement design tools (bogie; docs/pavement.md, 'Sharing factors').",
    "A design tool bins a group's total load (load spectra, ESA/SAR counts) and cannot see how the group shares it.",
    "factor_k<k> [-]: the group's damage as it shares its load over the same group shared equally, each axle counted",
    "  as a load of its own, sum_i (W_i/80 kN)^k / (n (W_mean/80 kN)^k), over the groups of the row (ratio of sums).",
    "guide_factor_k<k> [-]: what multiplies the group's count in Austroads' SAR_k (group loads 135 kN tandem, 181 kN",
    "  tri-axle): 1 + (D - D_eq) / D_group. At k = 4 the two agree within 3 %; at k = 12 the guide factor is the one",
    "  to apply to a SAR12 count. _low, _high: the 95 % interval over the groups (bootstrap, or the delta method).",
    "k: 4 overall (ESA), 5 asphalt fatigue, 7 subgrade rutting, 12 cemented layers (Austroads AGPT02 chapter 7).",
    "source: simulated (the fleet of params.yaml), observed (a WIM or weighbridge file), calibrated (the fleet at the",
    "  posterior's medians, fitted to that file; its interval over the groups only); protocol: static or wim;",
    "suspension: steel or air (simulated, calibrated), 'as observed' (a survey does not say); n_groups: laden groups.",
    "Limits: a factor holds for the groups, loads and pavements it came from; multiply a group's equivalent damage",
    "  by it, not its load.",
)


def sharing_factors(wear: pd.DataFrame, exponents: Mapping[str, float], **labels: str) -> pd.DataFrame:
    """The sharing factors of a wear table by group (:func:`with_group_baseline`'s columns): per row its key
    columns, ``labels`` as constant columns (e.g. ``source="observed"``), ``n_groups`` and per exponent name with
    value ``k``: ``factor_k<k>`` = 1 + ``extra_wear_<name>`` (D / D_eq) and ``guide_factor_k<k>`` = 1 +
    ``extra_wear_group_<name>``, each with ``_low`` and ``_high`` [-] (``SHARING_FACTORS_HEADER`` says what each
    is)."""
    keys = [c for c in ("source", "protocol", "group", "position", "suspension") if c in wear.columns or c in labels]
    out = pd.DataFrame({c: labels[c] if c in labels else wear[c].astype(str) for c in keys}, index=wear.index)
    out["n_groups"] = wear["n_groups"].to_numpy() if "n_groups" in wear.columns else np.zeros(len(wear), dtype=int)
    for name, k in exponents.items():
        for prefix, column in (("factor", f"extra_wear_{name}"), ("guide_factor", f"extra_wear_group_{name}")):
            for tail in ("", "_low", "_high"):
                values = wear[column + tail] if column + tail in wear.columns else math.nan
                out[f"{prefix}_k{k:g}{tail}"] = 1.0 + pd.to_numeric(values)
    return out.reset_index(drop=True)


def write_sharing_factors(frame: pd.DataFrame, path: str | Path) -> None:
    """Write ``frame`` (:func:`sharing_factors`) to ``path`` as csv after :data:`SHARING_FACTORS_HEADER`, each line
    a comment ("# "), numbers to 6 significant digits (a spreadsheet shows the comments as the first rows; pandas
    reads it with ``comment="#"``); written to a ``.partial`` file renamed at the end, so that a failure leaves no
    partial file."""
    target = Path(path)
    partial = target.with_name(target.name + ".partial")  # written whole, then renamed: no partial file is left
    try:
        with open(partial, "w", encoding="utf-8", newline="") as fh:
            fh.writelines(f"# {line}\n" for line in SHARING_FACTORS_HEADER)
            frame.to_csv(fh, index=False, float_format="%.6g", lineterminator="\n")
        os.replace(partial, target)
    finally:
        partial.unlink(missing_ok=True)
