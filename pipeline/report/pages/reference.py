"""Reproduction of the reference: its Figure 2, the linear runs L01-L03 and the non-linear step runs.

The reference's named cases are rerun here (:func:`reference_runs`, about a second with a warm numba cache); the
captions quote what the reference reported (:data:`REFERENCE_SAID`) beside our numbers.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from bogie import metrics
from bogie.plotting import case_history, figure2
from bogie.presets import triaxle_stage1
from bogie.results import DynamicResult
from bogie.steel import cases, fe
from bogie.steel.static import nondimensional_loads
from pipeline.report import text
from pipeline.report.context import Context, Page
from pipeline.report.layout import adopt_page, new_page, text_block

__all__ = [
    "REFERENCE_RUNS",
    "REFERENCE_SAID",
    "figure2_page",
    "figure2_verdict",
    "linear_verdict",
    "step_verdicts",
    "figure2_pages",
    "linear_pages",
    "reference_runs",
    "step_runs",
    "step_runs_page",
    "step_titles",
]

SECTION = "Reproduction of the reference"
#: the reference runs the report reproduces: three linear, then the non-linear step runs
REFERENCE_RUNS: tuple[str, ...] = ("L01", "L02", "L03", "N10", "N19", "N20", "N21")
LINEAR_RUNS, STEP_RUNS = REFERENCE_RUNS[:3], REFERENCE_RUNS[3:]
#: what the reference said of each reproduced run (its own words, quoted), and which of its figures show it
REFERENCE_SAID = {
    "L01": (
        "Figures 5-8",
        '"At this speed a steady state is achieved with each wheel on the step, with a rapidly '
        'damped oscillation at the start and end of the lift."',
    ),
    "L02": (
        "Figures 9-12",
        'the step is traversed in about a third of a second; "much higher wheel loads are '
        'generated with greater inequality between the two."',
    ),
    "L03": (
        "Figure 15",
        '"good equalisation over the two steady state regions", although "spikes occur in the plot '
        'at the times when a wheel rises over the front edge or falls off the rear edge."',
    ),
    "N10": ("Figure 16", "zero friction and zero bush stiffness"),
    "N19": ("Figure 17", "contact points fixed (linear constraints)"),
    "N20": ("Table 2", "rolling contact (non-linear constraints)"),
    "N21": ("Table 2", "long equaliser arm"),
}


#: a value "of the reference's size": ours within this factor of the reference's, either way; a convention of this
#: report (the reference states no tolerance, and its two-axle geometry is lost: docs/validation.md) [-]
SIZE_FACTOR = 2.0
#: each linear run's finding (docs/validation.md's table): what it says, the two runs compared by peak p, and the
#: ratio of their peaks it asks for (first over second below it): "better" asks below 1, "much worse" below 1/2, the
#: latter a convention of this report (the reference's own ratios are 0.70 and 0.21; tests/test_cases.py holds ours to
#: the stricter 0.25 and 1/3)
LINEAR_FINDINGS = {
    "L01": ("a soft bush (L03) equalises better than this stiff one at the same low speed", ("L03", "L01"), 1.0),
    "L02": ("at high speed equalisation is much worse than at low speed (L01)", ("L01", "L02"), 0.5),
    "L03": ("a soft bush equalises better than a stiff one (L01) at low speed", ("L03", "L01"), 1.0),
}


def linear_verdict(name: str, peaks: Mapping[str, float], reference: Mapping[str, float]) -> dict[str, Any]:
    """The verdict on a linear run: does the reference's finding hold in ours, is its peak p of the reference's size.

    Parameters
    ----------
    name
        The run (a key of :data:`LINEAR_FINDINGS`).
    peaks, reference
        Run name -> our and the reference's peak p (Table 1) of every run the finding compares [-].

    Returns
    -------
    dict
        ``finding`` (words), ``pair`` (the runs compared), ``holds`` (bool), ``ours`` and ``theirs`` (the ratio of the
        pair's peaks, ours and the reference's), ``limit`` (the finding's factor), ``size`` (our peak over the
        reference's) and ``same_size`` (within :data:`SIZE_FACTOR` either way).
    """
    finding, (a, b), limit = LINEAR_FINDINGS[name]
    ours, theirs = peaks[a] / peaks[b], reference[a] / reference[b]
    size = peaks[name] / reference[name]
    return {
        "finding": finding,
        "pair": (a, b),
        "holds": bool(ours < limit),
        "ours": ours,
        "theirs": theirs,
        "limit": limit,
        "size": size,
        "same_size": bool(1.0 / SIZE_FACTOR <= size <= SIZE_FACTOR),
    }


def step_verdicts(
    front: Mapping[str, float], reference: Mapping[str, tuple[float, float]], l03_mean: float
) -> list[dict[str, Any]]:
    """The verdicts on the step runs: the reference's three findings of its Figures 15-17 and Table 2.

    ``front``: run -> our P1 with the front wheel on the step [N]; ``reference``: run -> the reference's front and
    rear P1 [N]; ``l03_mean``: our linear L03's mean P1 [N]. Each verdict: ``finding`` (words), ``pair`` (the runs
    compared), ``holds`` (bool), ``ours`` and ``theirs`` (the ratio it rests on; ``theirs`` None where the reference
    gives no figure in newtons: its L03 is in Table 1's non-dimensional P1).
    """
    theirs = {n: v[0] for n, v in reference.items()}
    ours = {**front, "L03": l03_mean}
    # "well below" as under half and "substantial" as over four times are this report's conventions: the reference's
    # words give no number (its own ratios, 0.13 for N19 / N20, are shown beside ours)
    checks = (
        ("fixed contact points (N19) cut P1 well below rolling contacts (N20)", "N19", "N20", 0.5),
        ("a long equaliser arm (N21) cuts P1 below the standard arm (N20)", "N21", "N20", 1.0),
        ("where the linear L03 equalises, the non-linear N10 leaves a substantial difference", "L03", "N10", 0.25),
    )
    return [
        {
            "finding": words,
            "pair": (a, b),
            "holds": bool(ours[a] / ours[b] < limit),
            "ours": ours[a] / ours[b],
            "theirs": theirs[a] / theirs[b] if a in theirs else None,
        }
        for words, a, b, limit in checks
    ]


def reference_runs() -> dict[str, DynamicResult]:
    """Run the reference's named cases the report reproduces (:data:`REFERENCE_RUNS`), by name."""
    return {name: cases.run(name) for name in REFERENCE_RUNS}


def _p1_newtons(result: DynamicResult) -> np.ndarray:
    """P1 (Equation 4) of a run's wheel loads in newtons, at every step."""
    return np.asarray(metrics.p1(result.wheel_loads))


# ---- Figure 2 ------------------------------------------------------------------------------------------------------
def figure2_page(raw_params: Mapping[str, Any]) -> Page:
    """Figure 2 with params.yaml's ``figure2`` settings and our finite element points (Stage 1, no drag links)."""
    f2 = raw_params.get("figure2") or {}
    slopes = tuple(float(s) for s in f2.get("slopes_deg", (0.0, 0.5, 1.0, 1.5, 2.0)))
    alpha = float(f2.get("chassis_deflection_mm", 57.0)) / 1e3
    points = fe.figure2_points(slopes_deg=slopes, chassis_deflection=alpha)
    fig2 = figure2(q_max=float(f2.get("q_max", 20.0)), slopes_deg=slopes, chassis_deflection=alpha, fe_points=points)
    page = adopt_page(fig2, "Reference: Figure 2, static equalisation (Stages 1 and 2)", (0.1, 0.48, 0.8, 0.45))
    stage1 = triaxle_stage1()
    spacing = stage1.axle_x[1] - stage1.axle_x[0]
    algebra = [
        float(metrics.p(nondimensional_loads(q, np.radians(s) * spacing / alpha))) for s, (q, _) in points.items()
    ]
    caption = text.render(
        "figure2.j2",
        alpha=alpha,
        q=next(iter(points.values()))[0],
        slopes=list(points),
        fe_p=[v[1] for v in points.values()],
        algebra=algebra,
        verdict=figure2_verdict([v[1] for v in points.values()], algebra),
    )
    text_block(page, 0.45, caption)
    return Page(SECTION, "reference_figure2", page)


#: the finite element points "agree" with Equation 1 when every one is within this share of the largest p; a
#: convention of this report (the reference says only "good agreement") [-]
FE_AGREEMENT = 0.1


def figure2_verdict(fe_p: Sequence[float], algebra: Sequence[float]) -> dict[str, Any]:
    """The verdict on Figure 2: do our finite element points agree with Equation 1, as the reference's did.

    ``fe_p``, ``algebra``: p of the finite element model and of Equation 1 at each slope. Returns ``gap`` (the largest
    difference over the largest p of Equation 1), ``holds`` (``gap`` within :data:`FE_AGREEMENT`) and ``limit``.
    """
    gap = max(abs(f - a) for f, a in zip(fe_p, algebra)) / max(max(abs(a) for a in algebra), 1e-12)
    return {"gap": gap, "holds": bool(gap <= FE_AGREEMENT), "limit": FE_AGREEMENT}


def figure2_pages(ctx: Context) -> list[Page]:
    """Page 6: the reference's Figure 2."""
    return [figure2_page(ctx.inputs.raw_params)]


# ---- linear runs ---------------------------------------------------------------------------------------------------
def linear_pages(ctx: Context) -> list[Page]:
    """Pages 7-9: the linear runs' histories (bogie.plotting.case_history) against the reference's Table 1."""
    pages = []
    peaks = {n: cases.summary(n, ctx.runs[n])["peak_p"] for n in LINEAR_RUNS}
    table1 = {n: cases.get(n).reference["peak_p"] for n in LINEAR_RUNS}
    for name in LINEAR_RUNS:
        run = ctx.runs[name]
        page = adopt_page(case_history(run), f"Reference: linear run {name} (Table 1)", (0.08, 0.3, 0.84, 0.63))
        figures, words = REFERENCE_SAID[name]
        caption = text.render(
            "linear.j2",
            name=name,
            figures=figures,
            words=words,
            ours=cases.summary(name, run),
            reference=cases.get(name).reference,
            verdict=linear_verdict(name, peaks, table1),
        )
        text_block(page, 0.28, caption)
        pages.append(Page(SECTION, f"reference_{name}", page))
    return pages


# ---- non-linear step runs ------------------------------------------------------------------------------------------
def step_titles(ours: Mapping[str, Mapping[str, float]], refs: Mapping[str, tuple[float, float]]) -> dict[str, str]:
    """Panel titles of the step runs: what each run is, our and the reference's P1 front / rear [N]."""
    return {
        n: f"{n}: {REFERENCE_SAID[n][1]}\nours {v['p1_front_on_step']:.0f} / {v['p1_rear_on_step']:.0f} N, "
        f"reference {refs[n][0]:.0f} / {refs[n][1]:.0f} N"
        for n, v in ours.items()
    }


def step_runs_page(
    histories: Mapping[str, tuple[np.ndarray, np.ndarray]],
    linear: tuple[np.ndarray, np.ndarray],
    reference: Mapping[str, tuple[float, float]],
    titles: Mapping[str, str],
    caption: Sequence[str],
) -> Figure:
    """The non-linear step runs against the linear L03: P1 [N] histories, the reference's figures as lines.

    Parameters
    ----------
    histories
        Run name -> (time [s], P1 [N]) of the non-linear runs.
    linear
        (time [s], P1 [N]) of L03.
    reference
        Run name -> the reference's P1 with the front and with the rear wheel on the step [N].
    titles
        Run name -> panel title.
    caption
        Paragraphs under the charts.
    """
    fig = new_page("Reference: the non-linear step runs against the linear L03", body=(0.06, 0.36, 0.88, 0.57))
    axes = fig.subplots(2, 2, sharex=True, sharey=True).ravel()
    for ax, (name, (t, p1)) in zip(axes, histories.items()):
        ax.plot(linear[0], linear[1] / 1e3, color="0.55", lw=1.0, ls="--", label="L03 (linear, soft bush)")
        ax.plot(t, p1 / 1e3, color="C3", lw=1.1, label="non-linear run")
        front, rear = reference[name]
        ax.axhline(front / 1e3, color="C0", lw=0.9, ls=":", label="reference, front wheel on step")
        ax.axhline(rear / 1e3, color="C2", lw=0.9, ls=":", label="reference, rear wheel on step")
        ax.set_title(titles[name], fontsize=8.5)
        ax.set_ylabel("P1 (Equation 4) [kN]")
    # one legend, in the panel whose curves stay lowest (the most free space above them)
    peaks = [max(np.max(p1), *reference[name]) for name, (_, p1) in histories.items()]
    axes[int(np.argmin(peaks))].legend(loc="upper right")
    for ax in axes[2:]:
        ax.set_xlabel("time [s]")
    text_block(fig, 0.34, caption, size=8.2)
    return fig


def step_runs(ctx: Context) -> list[Page]:
    """Page 10: the non-linear step runs N10, N19, N20, N21 against L03 and the reference's Table 2."""
    runs = ctx.runs
    summaries = {n: cases.summary(n, runs[n]) for n in STEP_RUNS}
    table2 = {n: cases.get(n).reference for n in STEP_RUNS}
    refs = {n: (r["p1_front_on_step"], r["p1_rear_on_step"]) for n, r in table2.items()}
    l03 = runs["L03"]
    caption = text.render(
        "step_runs.j2",
        refs=refs,
        front={n: v["p1_front_on_step"] for n, v in summaries.items()},
        l03_mean=float(np.mean(_p1_newtons(l03))),
        verdicts=step_verdicts(
            {n: v["p1_front_on_step"] for n, v in summaries.items()}, refs, float(np.mean(_p1_newtons(l03)))
        ),
    )
    fig = step_runs_page(
        {n: (runs[n].t, _p1_newtons(runs[n])) for n in STEP_RUNS},
        (l03.t, _p1_newtons(l03)),
        refs,
        step_titles(summaries, refs),
        caption,
    )
    return [Page(SECTION, "reference_step_runs", fig)]
