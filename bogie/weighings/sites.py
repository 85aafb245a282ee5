"""Many WIM sites side by side (issue 46 Must 1): which sites see the most unequal sharing, with intervals, and which
site disagrees with the rest of the network.

A site is a file of records, or one station of a file that holds several (a state-wide TMG file's station column).
Each site's tandems and tri-axles are counted as :func:`bogie.weighings.stats.survey_statistics` counts them: the
groups, those outside 5 % and those over 10 % (``docs/weighings.md``). Per site and size:

* each share's 95 % Wilson interval (:func:`bogie.intervals.wilson_interval`, the design table's and the road
  figures' interval);
* each share against the same share of the other sites that agree with each other, pooled, by the two-proportion z
  test with the pooled variance: z = (p_s - p_r) / sqrt(p (1 - p) (1 / n_s + 1 / n_r)), p = (k_s + k_r) / (n_s +
  n_r), two-sided p-value erfc(|z| / sqrt 2) (a normal approximation: good when each of the four counts k and n - k
  of the site and of the rest is at least about 5, a rule of thumb and an assumption here, :data:`FEWEST`; the table
  says ``few`` otherwise and flags nothing on it);
* ``disagrees`` when a site's p-value for either share is below 0.05 / (2 m), m the sites of that size: Bonferroni's
  correction for the 2 m tests, so that a network of sites that all share one truth flags any site in at most about
  5 % of surveys. Step by step: the most extreme site under the threshold is flagged and leaves the reference of
  every later test, until no site is under it (one odd site would otherwise pull the pooled share of the others'
  rest towards itself and make a site that agrees with the others look odd too).

A site that disagrees sees a different sharing: its fleet (other trailers, other loading) or its site (a rougher
road, a biased sensor) may be why; the counts alone cannot tell which.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np
import pandas as pd

from bogie.intervals import wilson_interval

__all__ = ["COUNT_KEYS", "SITE_COLUMNS", "compare_sites", "counts_of_statistics", "share_text", "sites_text"]

#: what each site gives per size: groups, groups outside 5 %, groups over 10 % [-]; and the mean spread [kg]
COUNT_KEYS = ("n_groups", "n_outside_5pct", "n_over_10pct", "mean_spread_kg")
#: the columns of :func:`compare_sites`
SITE_COLUMNS = (
    "group", "site", "n_groups", "n_outside_5pct", "n_over_10pct", "share_outside_5pct", "share_outside_5pct_low",
    "share_outside_5pct_high", "p_outside_5pct", "share_over_10pct", "share_over_10pct_low", "share_over_10pct_high",
    "p_over_10pct", "mean_spread_kg", "few", "disagrees",
)  # fmt: skip
#: each share's count column and share column, in the order the table gives them
SHARES = (("n_outside_5pct", "share_outside_5pct"), ("n_over_10pct", "share_over_10pct"))
#: a count below which the z test's normal approximation is not trusted (each of k and n - k, site and rest): the
#: textbook rule of thumb for a normal approximation to a binomial, an assumption here, not a sourced threshold
FEWEST = 5
#: the network's family-wise level of the disagreement flags (Bonferroni over every test of one size) [-]
FAMILY_LEVEL = 0.05


def counts_of_statistics(statistics: pd.DataFrame) -> dict[str, dict[str, float]]:
    """A site's counts per size from its :func:`bogie.weighings.stats.survey_statistics` table (one row per
    ``group``): the shares times the groups, exact as whole numbers (a share is a count over ``n_groups``)."""
    out: dict[str, dict[str, float]] = {}
    for row in statistics.to_dict("records"):
        n = int(row["n_groups"])
        out[str(row["group"])] = {
            "n_groups": n, "n_outside_5pct": int(round(row["share_outside_5pct"] * n)),
            "n_over_10pct": int(round(row["share_over_10pct"] * n)), "mean_spread_kg": float(row["mean_spread_kg"]),
        }  # fmt: skip
    return out


def _z_test(k: int, n: int, k_rest: int, n_rest: int) -> tuple[float, bool]:
    """Two-sided p-value of the pooled two-proportion z test of k / n against k_rest / n_rest, and whether a count is
    below :data:`FEWEST` (then the p-value is still given, not trusted)."""
    few = min(k, n - k, k_rest, n_rest - k_rest) < FEWEST
    if n == 0 or n_rest == 0:
        return math.nan, True
    pooled = (k + k_rest) / (n + n_rest)
    if pooled in (0.0, 1.0):  # every group of the network on one side: no difference to test
        return 1.0, few
    z = (k / n - k_rest / n_rest) / math.sqrt(pooled * (1.0 - pooled) * (1.0 / n + 1.0 / n_rest))
    return math.erfc(abs(z) / math.sqrt(2.0)), few


def _stepwise(given: Mapping[str, Mapping[str, Any]], key: str, threshold: float) -> dict[str, tuple]:
    """Per site: (p-value, few, flagged) of its count ``key`` against the sites that agree, step by step: each site
    against the other sites not yet flagged; the smallest trusted p-value under ``threshold`` is flagged and left out
    of every reference after it; until none is. So one odd site does not make the others look odd by pulling the
    pooled share of their rest towards itself. Of two sites left that differ, both are flagged."""
    flagged: dict[str, tuple] = {}
    while True:
        agree = {name: c for name, c in given.items() if name not in flagged}
        k_all = sum(int(c[key]) for c in agree.values())
        n_all = sum(int(c["n_groups"]) for c in agree.values())
        tested = {}
        for name, c in agree.items():
            k, n = int(c[key]), int(c["n_groups"])
            tested[name] = _z_test(k, n, k_all - k, n_all - n) if len(agree) > 1 else (math.nan, True)
        trusted = [(p, name) for name, (p, few) in tested.items() if not few and p < threshold]
        if not trusted:
            return {**{name: (p, few, False) for name, (p, few) in tested.items()}, **flagged}
        p, name = min(trusted)
        # of two sites left that differ neither is the odd one: both are flagged
        for odd in agree if len(agree) == 2 else (name,):
            flagged[odd] = (tested[odd][0], False, True)


def compare_sites(sites: Mapping[str, Mapping[str, Mapping[str, Any]]]) -> pd.DataFrame:
    """The sites side by side, per size, the most unequal sharing first.

    Parameters
    ----------
    sites
        Site name -> size (``tandem``, ``triaxle``) -> :data:`COUNT_KEYS` (``n_groups``, ``n_outside_5pct``,
        ``n_over_10pct`` [-] whole numbers; ``mean_spread_kg`` [kg], None or NaN for no group), as
        :func:`counts_of_statistics` gives them. At least two sites.

    Returns
    -------
    pandas.DataFrame
        :data:`SITE_COLUMNS`, one row per size and site with groups of that size, sorted by size, then by share
        outside 5 % (largest first), then by name: the counts, the shares [-] and their 95 % Wilson intervals, the
        p-values of each share against the sites that agree pooled [-], the mean spread [kg], ``few`` (for both
        shares a count under :data:`FEWEST`: neither share is tested; one share with such a count is not) and
        ``disagrees`` (either p-value under :data:`FAMILY_LEVEL` / (2 m), step by step).

    Raises
    ------
    ValueError
        Fewer than two sites, or a count that is not a whole number in [0, n_groups].
    """
    if len(sites) < 2:
        raise ValueError(f"sites: {len(sites)} given; comparing sites needs at least 2")
    rows = []
    for size in sorted({size for entry in sites.values() for size in entry}):
        given = {name: entry[size] for name, entry in sites.items() if entry.get(size, {}).get("n_groups", 0) > 0}
        if not given:  # a size no site saw (a network of tandems alone): no row, nothing to test
            continue
        for name, c in given.items():
            for key, _ in SHARES:
                if not (float(c[key]).is_integer() and 0 <= c[key] <= c["n_groups"]):
                    raise ValueError(f"sites[{name!r}][{size!r}][{key!r}] = {c[key]!r}: must be a whole number in "
                                     f"[0, n_groups = {c['n_groups']}] [-]")  # fmt: skip
        threshold = FAMILY_LEVEL / (2 * len(given))
        tests = {key: _stepwise(given, key, threshold) for key, _ in SHARES}
        for name, c in given.items():
            n = int(c["n_groups"])
            row: dict[str, Any] = {"group": size, "site": name, "n_groups": n}
            for key, share in SHARES:
                k = int(c[key])
                low, high = wilson_interval(np.array([k]), np.array([n]))
                row.update({key: k, share: k / n, f"{share}_low": float(low[0]), f"{share}_high": float(high[0]),
                            f"p_{share.removeprefix('share_')}": tests[key][name][0]})  # fmt: skip
            row["few"] = all(tests[key][name][1] for key, _ in SHARES)
            row["disagrees"] = any(tests[key][name][2] for key, _ in SHARES)
            spread = c.get("mean_spread_kg")
            row["mean_spread_kg"] = math.nan if spread is None else float(spread)
            rows.append(row)
    frame = pd.DataFrame(rows, columns=list(SITE_COLUMNS))
    if len(frame):
        frame = frame.sort_values(["group", "share_outside_5pct", "site"], ascending=[True, False, True])
    return frame.reset_index(drop=True)


def share_text(share: float, low: float, high: float) -> str:
    """A share and its interval in per cent, as the table prints them: ``" 75.0 (59.8- 85.8)"``."""
    return f"{100 * share:5.1f} ({100 * low:4.1f}-{100 * high:5.1f})"


def sites_text(frame: pd.DataFrame) -> str:
    """:func:`compare_sites`' table as ``bogie weighings --by-site`` prints it: per size, each site's groups, shares
    outside 5 % and over 10 % with their 95 % intervals [%], mean spread [kg] and flag, then all sites pooled."""
    lines = [
        "sites side by side, the most unequal sharing first (95 % Wilson intervals; docs/weighings.md, 'Many sites'):",
        f"{'group':<8} {'site':<24} {'n':>6} {'outside 5 % [%]':>22} {'over 10 % [%]':>22} {'spread [kg]':>11}  flag",
    ]
    for size, part in frame.groupby("group", sort=True):
        for row in part.to_dict("records"):
            shares = [share_text(row[s], row[f"{s}_low"], row[f"{s}_high"]) for _, s in SHARES]
            flag = "disagrees" if row["disagrees"] else ("few" if row["few"] else "")
            spread = "-" if math.isnan(row["mean_spread_kg"]) else f"{row['mean_spread_kg']:.0f}"
            lines.append(f"{size:<8} {row['site'][:24]:<24} {row['n_groups']:>6} {shares[0]:>22} {shares[1]:>22} "
                         f"{spread:>11}  {flag}".rstrip())  # fmt: skip
        n = int(part["n_groups"].sum())
        pooled = []
        for key, _ in SHARES:
            k = int(part[key].sum())
            low, high = wilson_interval(np.array([k]), np.array([n]))
            pooled.append(share_text(k / n, low[0], high[0]))
        lines.append(f"{size:<8} {f'all {len(part)} sites':<24} {n:>6} {pooled[0]:>22} {pooled[1]:>22}")
    lines += [
        f"flag: disagrees = a share differs from the pooled share of the sites that agree (two-proportion z test, p "
        f"under {FAMILY_LEVEL:g} / (2 x sites), Bonferroni);",
        f"few = counts under {FEWEST}, neither share tested (nor is one share with such a count). A site that "
        "disagrees has another fleet, or another road or sensor: the counts cannot tell which.",
    ]
    return "\n".join(lines)
