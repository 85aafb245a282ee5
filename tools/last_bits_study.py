"""How much a last-bit difference moves the simulated weighings (``docs/architecture.md``, "How much a last bit moves").

``python tools/last_bits_study.py [--n-bogies 200]`` samples a reduced fleet from params.yaml (its design,
distributions and seed; ``fleet.n_bogies`` replaced) and weighs every bogie statically and by WIM three times, each in
its own child process:

* ``reference``: as the stages do (numba compiling for x86-64-v3);
* ``ulp``: the same, with every sampled chassis tilt moved by one ulp (``numpy.nextafter``): the smallest change an
  input can have, what a different rounding of a sample's inverse CDF would give;
* ``no FMA``: numba compiling for a generic x86-64 CPU (``NUMBA_CPU_NAME=generic``): no fused multiply-adds, so
  nearly every operation of the kernels rounds differently, as another compiler target or architecture would.

It prints, for each variant against the reference and each protocol, the share of runs whose result differs at all,
the median and largest relative difference of the largest axle-load deviation and the spread, how many of the
survey's flags (outside 5 %, over 10 %) flipped, and which bogies differ most with their friction settings. About
15 s with the kernels compiled; 2-3 minutes the first time (the ``no FMA`` child compiles them for its target).
"""

from __future__ import annotations

import argparse
import os
import pickle
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
COLUMNS = ("max_deviation", "spread_kg")
#: the survey's flags of a run: a flip changes a share the survey counts
FLAGS = ("outside_5pct", "over_10pct")


def _weigh(n_bogies: int, ulp: bool, out: str) -> None:
    """Child: weigh the reduced fleet, pickle the run rows to ``out``."""
    import numpy as np
    import pandas as pd

    from bogie.fleet import sample_fleet, weigh_fleet
    from pipeline.config import load_config  # params.yaml's one reader; the study is bogie.fleet's

    config = load_config(ROOT / "params.yaml")
    fleet = sample_fleet(config.fleet_study, n_bogies, config.seed, config.fleet.sampling)
    if ulp:
        fleet["chassis_tilt"] = np.nextafter(fleet["chassis_tilt"].to_numpy(), np.inf)
    runs = weigh_fleet(fleet, {name: getattr(config.protocol, name) for name in config.protocol.run})
    pd.to_pickle(runs, out)


def _child(variant: str, n_bogies: int, out: str) -> None:
    env = dict(os.environ)
    if variant == "no FMA":
        env["NUMBA_CPU_NAME"] = "generic"
    code = f"import sys; sys.path.insert(0, {str(ROOT)!r}); from tools.last_bits_study import _weigh; " \
           f"_weigh({n_bogies}, {variant == 'ulp'}, {out!r})"  # fmt: skip
    subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=env, check=True)


def main(argv: list[str] | None = None) -> int:
    import numpy as np
    import pandas as pd

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n-bogies", type=int, default=200, help="bogies in the reduced fleet (default 200)")
    args = parser.parse_args(argv)
    frames = {}
    with tempfile.TemporaryDirectory() as tmp:
        for variant in ("reference", "ulp", "no FMA"):
            path = str(Path(tmp) / f"{variant}.pkl")
            _child(variant, args.n_bogies, path)
            with open(path, "rb") as fh:
                frames[variant] = pickle.load(fh)
    ref = frames["reference"]
    ok = ref["status"] == "ok"
    print(f"{args.n_bogies} fleet bogies, {int(ok.sum())} of {len(ref)} runs ok in the reference")
    print("variant  protocol  runs differing  " + "  ".join(f"{c}: median / largest rel. diff." for c in COLUMNS))
    for variant in ("ulp", "no FMA"):
        other = frames[variant]
        both = ok & (other["status"] == "ok")
        for protocol in ("static", "wim"):
            rows = both & (ref["protocol"] == protocol)
            a, b = ref.loc[rows], other.loc[rows]
            differ = np.zeros(int(rows.sum()), dtype=bool)
            stats = []
            for c in COLUMNS:
                x, y = a[c].to_numpy(float), b[c].to_numpy(float)
                differ |= x != y
                rel = np.abs(y - x) / np.maximum(np.abs(x), 1e-300)
                stats.append(f"{np.median(rel):.1e} / {np.max(rel):.1e}")
            flips = sum(int((a[f].astype(bool).to_numpy() != b[f].astype(bool).to_numpy()).sum()) for f in FLAGS)
            print(f"{variant:7}  {protocol:8}  {int(differ.sum()):4d} of {len(differ):4d}  " + "  ".join(stats)
                  + f"  {flips} flags flipped")  # fmt: skip
        rel = (other.loc[both, "max_deviation"] - ref.loc[both, "max_deviation"]).abs()
        worst = ref.loc[rel.sort_values(ascending=False).index[:5]]
        print(f"  {variant}: the runs whose max_deviation moved most (absolute, share of the group mean):")
        cols = ["sample_id", "protocol", "n_axles", "friction_coefficient", "spring_friction_band", "max_deviation"]
        print(pd.concat([worst[cols], rel.loc[worst.index].rename("moved")], axis=1).to_string(index=False))
    return 0


if __name__ == "__main__":
    sys.exit(main())
