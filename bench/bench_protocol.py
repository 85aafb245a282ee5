"""The two protocols (static weighbridge, WIM pass) on a fixed fleet sample: this tree against a reference commit.

Issue 15 asks for the new and the previous code in the same run on the same samples. Each tree is imported in its
own subprocess (``PYTHONPATH`` pointing at it, so nothing of one tree leaks into the other): this working tree as it
is (uncommitted changes included) and the reference commit (default: the merge base of HEAD and ``main``, the code
before this branch's changes) extracted with ``git archive`` into a cache directory keyed by its hash, reused by
later runs so that its numba cache stays warm. Every worker samples the
same :data:`N_BOGIES` fleet bogies (``params.yaml`` of this tree, ``fleet.n_bogies`` set to that), loads the
compiled kernels with one untimed weighing per protocol, then times :data:`PASSES` passes of
:func:`bogie.fleet.weighing.weigher.weigh` over the sample per protocol. Workers of the two trees alternate
(:data:`ROUNDS` rounds, which goes first alternating) so that a burst of other work on the shared machine falls on
both; the best pass of each protocol is kept. ``--reference HEAD`` with a clean tree times the same code twice: the
ratio it prints is the bench's own scatter.

Accuracy: the reference tree at dt / :data:`DT_DIVISOR` (both protocols) is the converged answer; the table gives,
per result column, the largest difference over the sample of each tree's dt = params.yaml run from it (rows where
both succeeded), and how many boolean flags differ. Absolute times depend on the machine and its load; compare the
ratio, printed with the load average. See ``bench/README.md``.

Run alone: ``python -m bench.bench_protocol [--reference REV]``.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
#: fleet bogies weighed by each worker [-]
N_BOGIES = 50
#: the accuracy reference runs at the protocols' dt divided by this [-]
DT_DIVISOR = 4
#: timed passes over the sample per protocol in one worker [-]
PASSES = 2
#: alternating worker rounds per tree [-]
ROUNDS = 3
#: where reference trees are extracted (one directory per commit hash)
TREE_CACHE = Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache")) / "bogie-bench-trees"
PROTOCOLS = ("static", "wim")
#: the float result columns compared (bogie.fleet.weighing.runs.RESULT_COLUMNS without the flags)
FLOAT_COLUMNS = (
    *(f"axle_load_{i + 1}" for i in range(6)), *(f"load_share_{i + 1}" for i in range(6)),
    "group_load", "p", "p1", "max_deviation", "spread", "spread_kg", "road_wear_factor", "chassis_pitch",
)  # fmt: skip
FLAG_COLUMNS = ("outside_5pct", "over_10pct", "wheel_airborne", "equaliser_on_stop")


# ---- the worker: runs inside the tree under test, imports nothing of this one ---------------------------------
def worker(out: str, params: str, n_bogies: int, divisor: int, passes: int) -> None:
    """Weigh the sample by both protocols ``passes`` times; write times [s], rows and the tree to ``out``."""
    import dataclasses

    import bogie
    from bogie.fleet.sampling.sample import bogie_from_sample
    from bogie.fleet.weighing.weigher import weigh
    from pipeline.config import load_config
    from pipeline.sample import sample_fleet

    config = load_config(params)
    config = dataclasses.replace(config, fleet=dataclasses.replace(config.fleet, n_bogies=n_bogies))
    records = sample_fleet(config).to_dict("records")
    bogies = [bogie_from_sample(r) for r in records]
    specs = {}
    for name in PROTOCOLS:
        spec = getattr(config.protocol, name)
        specs[name] = dataclasses.replace(spec, dt=spec.dt / divisor)
        if divisor > 1 and hasattr(spec, "step_tolerance"):  # the reference: fixed steps of dt / divisor
            specs[name] = dataclasses.replace(specs[name], step_tolerance=None)
    for name, spec in specs.items():  # loads the compiled kernels before any timing
        weigh(bogies[0], records[0], name, spec)
    times: dict[str, list[float]] = {name: [] for name in PROTOCOLS}
    rows: dict[str, list[dict]] = {}
    for _ in range(passes):
        for name, spec in specs.items():
            start = time.perf_counter()
            result = [weigh(b, r, name, spec) for b, r in zip(bogies, records)]
            times[name].append(time.perf_counter() - start)
            rows[name] = [
                {k: (None if v is None else (v if isinstance(v, str) else float(v))) for k, v in row.items()
                 if k in FLOAT_COLUMNS or k in FLAG_COLUMNS or k == "status"}
                for row in result
            ]  # fmt: skip
    groups = [str(r["group"]) for r in records]
    Path(out).write_text(json.dumps({"tree": bogie.__file__, "times": times, "rows": rows, "groups": groups}))


# ---- the driver -----------------------------------------------------------------------------------------------
def reference_tree(rev: str) -> tuple[str, Path]:
    """The commit ``rev`` as a directory of its files (extracted once per hash, then reused)."""
    sha = subprocess.run(
        ["git", "rev-parse", "--verify", f"{rev}^{{commit}}"], cwd=ROOT, check=True, capture_output=True, text=True
    ).stdout.strip()
    tree = TREE_CACHE / sha
    if not (tree / "bogie" / "__init__.py").exists():
        tree.mkdir(parents=True, exist_ok=True)
        archive = subprocess.run(["git", "archive", sha, "bogie", "pipeline", "params.yaml"], cwd=ROOT, check=True,
                                 capture_output=True).stdout  # fmt: skip
        subprocess.run(["tar", "-x", "-C", str(tree)], input=archive, check=True)
    return sha, tree


def merge_base() -> str:
    """The commit this branch started from (the merge base of HEAD and ``main``; HEAD itself on main)."""
    return subprocess.run(
        ["git", "merge-base", "HEAD", "main"], cwd=ROOT, check=True, capture_output=True, text=True
    ).stdout.strip()


def tree_env(tree: Path) -> dict[str, str]:
    """The environment of a process that imports ``tree``'s code (and its own numba cache beside it)."""
    env = dict(os.environ, PYTHONPATH=str(tree))
    env.pop("NUMBA_CACHE_DIR", None)
    return env


def run_worker(tree: Path, divisor: int = 1, passes: int = PASSES) -> dict:
    """One worker process importing ``tree`` with the tree's own params.yaml; its JSON answer."""
    env = tree_env(tree)
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "out.json"
        command = [sys.executable, str(Path(__file__).resolve()), "--worker", str(out), "--params",
                   str(tree / "params.yaml"), "--n", str(N_BOGIES), "--divisor", str(divisor),
                   "--passes", str(passes)]  # fmt: skip
        subprocess.run(command, cwd=tmp, env=env, check=True)
        answer = json.loads(out.read_text())
    if Path(answer["tree"]).resolve().parent.parent != tree.resolve():
        raise RuntimeError(f"worker for {tree} imported bogie from {answer['tree']}")
    return answer


def fine_reference(tree: Path, cache: Path | None) -> dict:
    """A tree's answer in fixed steps of dt / DT_DIVISOR; a reference tree's is kept beside it (``cache``)."""
    key = hashlib.sha256((tree / "params.yaml").read_bytes()).hexdigest()[:16]
    cached = None if cache is None else cache / f"fine-{DT_DIVISOR}-{N_BOGIES}-{key}.json"
    if cached is not None and cached.exists():
        return json.loads(cached.read_text())
    answer = run_worker(tree, divisor=DT_DIVISOR, passes=1)
    if cached is not None:
        cached.write_text(json.dumps(answer))
    return answer


def largest_differences(rows: list[dict], reference: list[dict]) -> dict[str, float]:
    """Per float column the largest |difference| over the rows where both succeeded; per flag the count differing."""
    both = [(a, b) for a, b in zip(rows, reference) if a["status"] == "ok" and b["status"] == "ok"]
    columns = [c for c in FLOAT_COLUMNS if c in reference[0]]
    worst = {c: max((abs(a[c] - b[c]) for a, b in both), default=float("nan")) for c in columns}
    worst.update({c: float(sum(a[c] != b[c] for a, b in both)) for c in FLAG_COLUMNS})
    worst["failed"] = float(sum(a["status"] != "ok" for a in rows))
    return worst


def main(reference: str | None = None) -> None:
    if reference is None:  # the commit this branch started from: the code before its changes
        reference = merge_base()
    sha, ref_tree = reference_tree(reference)
    load_before = os.getloadavg()
    print(f"{N_BOGIES} fleet bogies, this tree {ROOT} against {reference} = {sha[:10]} ({ref_tree})")
    start = " ".join(f"{x:.2f}" for x in load_before)
    print(f"load average at start: {start} on {os.cpu_count()} cores")
    best: dict[str, dict[str, float]] = {"this": {}, "reference": {}}
    answers: dict[str, dict] = {}
    for k in range(ROUNDS):
        order = (("this", ROOT), ("reference", ref_tree))
        for label, tree in order if k % 2 == 0 else order[::-1]:  # neither tree always goes first
            answer = run_worker(tree)
            answers[label] = answer
            for name in PROTOCOLS:
                t = min(answer["times"][name])
                best[label][name] = min(best[label].get(name, t), t)
    fine = fine_reference(ref_tree, ref_tree)
    own = fine_reference(ROOT, None)
    load_after = os.getloadavg()
    groups = answers["this"]["groups"]
    print(f"groups: {', '.join(f'{g} {groups.count(g)}' for g in sorted(set(groups)))}")
    print()
    print("| protocol | reference runs/s | this runs/s | speed-up |")
    print("|---|---|---|---|")
    for name in PROTOCOLS:
        ref_rate = N_BOGIES / best["reference"][name]
        new_rate = N_BOGIES / best["this"][name]
        print(f"| {name} | {ref_rate:.1f} | {new_rate:.1f} | {new_rate / ref_rate:.2f} x |")
    both_ref = 2 * N_BOGIES / (best["reference"]["static"] + best["reference"]["wim"])
    both_new = 2 * N_BOGIES / (best["this"]["static"] + best["this"]["wim"])
    print(f"| both | {both_ref:.1f} | {both_new:.1f} | {both_new / both_ref:.2f} x |")
    print()
    print(f"largest difference from a run in fixed steps of dt / {DT_DIVISOR} (flags and failed: counts of rows): the "
          "reference tree and this one each against the reference tree's, and this one against its own")  # fmt: skip
    for name in PROTOCOLS:
        ref_d = largest_differences(answers["reference"]["rows"][name], fine["rows"][name])
        new_d = largest_differences(answers["this"]["rows"][name], fine["rows"][name])
        own_d = largest_differences(answers["this"]["rows"][name], own["rows"][name])
        print(f"\n{name}:\n| column | reference | this | this against its own dt / {DT_DIVISOR} |\n|---|---|---|---|")
        for column in ref_d:
            print(f"| {column} | {ref_d[column]:.4g} | {new_d[column]:.4g} | {own_d[column]:.4g} |")
    print("\nlargest difference between the two trees at the same dt (0: the same results to the bit)")
    for name in PROTOCOLS:
        between = largest_differences(answers["this"]["rows"][name], answers["reference"]["rows"][name])
        column = max((c for c in between if c in FLOAT_COLUMNS), key=lambda c: between[c])
        print(f"{name}: {between[column]:.3g} ({column}); flags differing: {sum(between[c] for c in FLAG_COLUMNS):.0f}")
    print(f"\nload average at end: {load_after[0]:.2f} {load_after[1]:.2f} {load_after[2]:.2f}")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--reference", help="git revision to compare against (default: the merge base with main)")
    parser.add_argument("--worker", help=argparse.SUPPRESS)
    parser.add_argument("--params", help=argparse.SUPPRESS)
    parser.add_argument("--n", type=int, default=N_BOGIES, help=argparse.SUPPRESS)
    parser.add_argument("--divisor", type=int, default=1, help=argparse.SUPPRESS)
    parser.add_argument("--passes", type=int, default=PASSES, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker:
        worker(args.worker, args.params, args.n, args.divisor, args.passes)
    else:
        main(args.reference)
