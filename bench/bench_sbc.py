"""Do the calibration's posterior intervals hold their truths as often as they say? Simulation-based calibration of
the calibrate stage's posterior (issue 43's "done when"), with truths drawn from the priors.

One fixed truth in a prior's tail (``bench_calibrate``'s) cannot tell a fault of the intervals from bad luck: a 90 %
interval misses one truth in ten whatever is right. Here each of ``--surveys`` synthetic 5,000-vehicle surveys is made
from its own truth, drawn from the posterior's own priors within the fit's bounds
(:func:`bogie.fleet.calibration.priors.prior_draws`, the priors of :func:`~bogie.fleet.calibration.fitting.priors_for`),
on its own fleet and site (master seed ``--first-seed + i``: its own road, bogies and site bias), and calibrated
as the stage calibrates it: the prior-free minimum (the chains' start), then the posterior with params.yaml's draws,
chains and between-site covariance, on one table built once (the table depends on params.yaml, not on the survey).
The bootstrap, the checks and the attribution are left out: they do not change the posterior.

The table's bogies cross one site of their own (the params.yaml seed's): with one table for every survey its site's
departure from the average site is shared by all of them, so their ranks are not independent (the between-site
covariance in the likelihood allows for that departure, but one draw of it moves every survey's posterior the same
way). ``--table-per-survey`` builds each survey's table anew on its own site (master seed :data:`TABLE_SEED` + i),
as the method's randomness is drawn anew for each dataset in simulation-based calibration; about 100 s more each.
``--table-sites K`` spreads each table's bogies over K sites (``calibrate.table_sites``), the surveys still at one.

If the posterior is calibrated, each truth's rank among its posterior's draws (the share of draws below it) is
uniform on [0, 1] and each interval at ``confidence_level`` holds its truth with that probability (Talts et al. 2018,
"Validating Bayesian inference algorithms with simulation-based calibration", arXiv:1804.06788). Printed per
quantity: the truths, the ranks, the intervals that miss, and the count of misses against the binomial's 95 % range
for that many surveys; then every interval over all quantities, and how many posteriors piled at a bound or did not
converge. Each survey's rows go to ``--out`` (a csv) as they come, so a long run can be read before it ends, with the
log-likelihood at the truth and at the posterior's medians (a miss the likelihood makes, not the sampler, reads a
truth far less likely than the medians) and the truth's largest residual in the likelihood's sd.

Run alone: ``python -m bench.bench_sbc [--surveys N] [--skip K] [--first-seed S] [--vehicles V] [--out FILE]`` (2-3
minutes per survey on 2 cores); ``--skip K`` continues a run of K surveys (the same truths and seeds as one run of
K + N), ``--only Q,...`` fits only those quantities with the others held at their truths (the same truths and
surveys: a quantity's own bias apart from its trade-offs), and ``--summarise FILE...`` prints the summary of earlier
runs' csv files together.
"""

from __future__ import annotations

import argparse
import copy
import math
import os
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd
import yaml

from bench.bench_calibrate import FIT, N_VEHICLES

ROOT = Path(__file__).resolve().parent.parent
#: the first survey's master seed (survey i: FIRST_SEED + i), away from bench_calibrate's 777-779
FIRST_SEED = 9001
#: seed of the truths' draws from the priors
TRUTH_SEED = 43
#: with --table-per-survey, survey i's table is made with master seed TABLE_SEED + i (its site, bogies and CRN)
TABLE_SEED = 50001


def binomial_range(n: int, p: float, mass: float = 0.95) -> tuple[int, int]:
    """The central ``mass`` range of a binomial(n, p) count: the smallest k_low and largest k_high with at most
    (1 - mass) / 2 of the probability below and above."""
    pmf = [math.comb(n, k) * p**k * (1.0 - p) ** (n - k) for k in range(n + 1)]
    tail = (1.0 - mass) / 2.0
    low = next(k for k in range(n + 1) if sum(pmf[: k + 1]) > tail)
    high = next(k for k in range(n, -1, -1) if sum(pmf[k:]) > tail)
    return low, high


def main(argv: list[str] | None = None) -> None:
    from bogie.fleet.calibration import checks as K
    from bogie.fleet.calibration.fitting import priors_for
    from bogie.fleet.calibration.posterior import posterior
    from bogie.fleet.calibration.priors import default_priors, prior_draws
    from bogie.fleet.calibration.problem import fit, make_problem
    from pipeline import calibrate as C
    from pipeline.config import parse_config

    parser = argparse.ArgumentParser(prog="python -m bench.bench_sbc", description=__doc__.splitlines()[0])
    parser.add_argument("--surveys", type=int, default=10, help="synthetic surveys, each its own truth (default 10)")
    parser.add_argument("--first-seed", type=int, default=FIRST_SEED, help=f"first survey's seed ({FIRST_SEED})")
    parser.add_argument("--skip", type=int, default=0,
                        help="surveys of an earlier run: their truths drawn and passed over (default 0)")  # fmt: skip
    parser.add_argument("--vehicles", type=int, default=N_VEHICLES, help=f"survey size (default {N_VEHICLES})")
    parser.add_argument("--out", type=Path, default=Path("sbc.csv"), help="each survey's rows (default sbc.csv)")
    parser.add_argument("--table-per-survey", action="store_true",
                        help="each survey's table anew on its own site (seed TABLE_SEED + i)")  # fmt: skip
    parser.add_argument("--table-sites", type=int, default=None,
                        help="WIM sites the table's bogies are spread over (calibrate.table_sites; default: "
                        "params.yaml's); the surveys stay at one site each")  # fmt: skip
    parser.add_argument("--only", default=None,
                        help="fit only these quantities (comma-separated), the others held at their truths: one "
                        "quantity's own bias apart from its trade-offs (the full run's truths, surveys)")  # fmt: skip
    parser.add_argument("--summarise", type=Path, nargs="+", default=None,
                        help="only summarise these csv files of earlier runs together")  # fmt: skip
    args = parser.parse_args(argv)
    raw = yaml.safe_load((ROOT / "params.yaml").read_text())
    if args.summarise:
        rows = pd.concat([pd.read_csv(f) for f in args.summarise], ignore_index=True)
        summarise(rows, raw["calibrate"]["confidence_level"])
        return
    raw["calibrate"]["fit"] = copy.deepcopy(FIT)
    if args.table_sites is not None:
        raw["calibrate"]["table_sites"] = args.table_sites
    print(f"load average {os.getloadavg()[0]:.2f} {os.getloadavg()[1]:.2f} on {os.cpu_count()} CPUs", flush=True)
    start = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        raw["observed"].update(path="observed/synthetic.csv", format="csv")
        config = parse_config(raw)
        settings = C.method_settings(config)
        mapper = C.workers_map(config.execution)
        table = C.build_table(config, lambda text: None)
        base = C.defaults(config)
        print(f"table built in {time.perf_counter() - start:.0f} s", flush=True)
        names = [q for q in FIT]
        only = names if args.only is None else [q.strip() for q in args.only.split(",")]
        unknown = [q for q in only if q not in FIT]
        if unknown:
            parser.error(f"--only: {', '.join(unknown)} not fitted; the quantities are {', '.join(names)}")
        priors = default_priors(base, {q: t.mean_range() for q, t in table.tilted.items()})
        truths = prior_draws(priors, names, [tuple(FIT[q]) for q in names], args.skip + args.surveys,
                             np.random.default_rng(TRUTH_SEED))  # fmt: skip
        rows: list[dict] = []
        for i in range(args.skip, args.skip + args.surveys):
            t0 = time.perf_counter()
            truth = dict(zip(names, (float(v) for v in truths[i])))
            truth_raw = copy.deepcopy(raw)
            truth_raw["seed"] = args.first_seed + i
            truth_raw["calibrate"]["table_sites"] = 1  # the survey is made at one site, whatever the table's
            truth_raw["fleet"]["n_bogies"] = args.vehicles
            truth_raw["ablation"]["n_bogies"] = min(raw["ablation"]["n_bogies"], args.vehicles // 4)
            truth_raw["calibrate"]["n_bogies"] = args.vehicles
            made = parse_config(truth_raw)
            if args.table_per_survey:  # the table's own site is part of the method's randomness: drawn anew each time
                table_raw = copy.deepcopy(raw)
                table_raw["seed"] = TABLE_SEED + i
                table = C.build_table(parse_config(table_raw), lambda text: None)
            frame = K.filtered(K.simulate_fleet(C.crn_table(made), {**C.defaults(made), **truth}, executor=mapper), 0.0)
            survey = Path(tmp) / "observed" / "synthetic.csv"
            K.write_csv_survey(frame, survey)
            observed, _ = C.observed_groups(survey, config)
            held = {q: v for q, v in truth.items() if q not in only}  # the quantities not fitted, at their truths
            fitted = {q: FIT[q] for q in only}
            problem = make_problem(table, observed, fitted, {**base, **held}, config.observed.min_group_load)
            best, _, _ = fit(problem, settings.seed, settings.maxiter, settings.popsize)
            # the priors of the full fit (a prior centred on the base value, the sensor's, keeps params.yaml's centre)
            used = {q: p for q, p in priors_for(make_problem(table, observed, settings.fit, base,
                                                             config.observed.min_group_load), settings).items()
                    if q in only}  # fmt: skip
            post = posterior(problem, used, best, settings.posterior_draws, settings.seed, settings.confidence_level,
                             chains=settings.chains, sites=settings.sites, executor=mapper)  # fmt: skip
            seconds = time.perf_counter() - t0
            at = likelihood_at(post.likelihood, [truth[q] for q in problem.fitted],
                               [post.summary[q]["median"] for q in problem.fitted])  # fmt: skip
            for q in only:
                s, draws = post.summary[q], post.draws[q].to_numpy()
                rows.append({
                    "survey": i, "seed": args.first_seed + i, "quantity": q, "truth": truth[q],
                    "median": s["median"], "low": s["low"], "high": s["high"],
                    "inside": bool(s["low"] <= truth[q] <= s["high"]), "rank": float(np.mean(draws < truth[q])),
                    "piled": s["piled"], "rhat": s["rhat"], "ess_bulk": s["ess_bulk"], "converged": post.converged,
                    "seconds": seconds, **at,
                })  # fmt: skip
            pd.DataFrame(rows).to_csv(args.out, index=False)
            missed = [r["quantity"] for r in rows if r["survey"] == i and not r["inside"]]
            print(f"survey {i} (seed {args.first_seed + i}) in {seconds:.0f} s, load {os.getloadavg()[0]:.2f}: "
                  f"misses {missed or 'none'}; converged {post.converged}; log-likelihood at the truth "
                  f"{at['loglike_truth']:.1f}, at the medians {at['loglike_median']:.1f}; the truth's largest residual "
                  f"z {at['worst_z_truth']:+.1f} (summary {at['worst_summary']})", flush=True)  # fmt: skip
    summarise(pd.DataFrame(rows), settings.confidence_level)
    print(f"total {time.perf_counter() - start:.0f} s; load average {os.getloadavg()[0]:.2f} after")


def likelihood_at(like, truth: list[float], medians: list[float]) -> dict[str, float]:
    """Whether a miss is the likelihood's or the sampler's: the synthetic log-likelihood at the truth and at the
    posterior's medians (a truth far less likely than the medians: the likelihood prefers another fleet, whatever the
    sampler does), and the truth's largest residual in sd of the likelihood's covariance, with its summary's index
    (:func:`bogie.fleet.calibration.posterior.summaries`' order)."""
    t = np.asarray(truth, dtype=float)
    z = (like.observed - like.simulated(t)) / np.sqrt(np.diag(np.linalg.inv(like.precision)))
    k = int(np.nanargmax(np.abs(z)))
    return {"loglike_truth": float(like(t)), "loglike_median": float(like(np.asarray(medians, dtype=float))),
            "worst_z_truth": float(z[k]), "worst_summary": k}  # fmt: skip


def summarise(rows: pd.DataFrame, level: float) -> None:
    """Per quantity: the misses against the binomial range, the ranks; then all intervals together."""
    n = rows["survey"].nunique()
    low, high = binomial_range(n, 1.0 - level)
    print(f"{n} surveys, {level:.0%} intervals: each quantity's misses should lie in [{low}, {high}] (binomial 95 %)")
    for q, part in rows.groupby("quantity", sort=False):
        ranks = " ".join(f"{r:.2f}" for r in part["rank"])
        misses = int((~part["inside"].astype(bool)).sum())
        flag = "" if low <= misses <= high else "  OUTSIDE the binomial range"
        print(f"  {q:28s} misses {misses}/{n}{flag}; ranks {ranks}")
    total = len(rows)
    misses = int((~rows["inside"].astype(bool)).sum())
    t_low, t_high = binomial_range(total, 1.0 - level)
    print(f"all intervals: {misses} of {total} miss (binomial 95 % range [{t_low}, {t_high}]); "
          f"piled at a bound: {int(rows['piled'].notna().sum())}; surveys unconverged: "
          f"{int((~rows.groupby('survey')['converged'].first().astype(bool)).sum())}")  # fmt: skip


if __name__ == "__main__":
    main()
