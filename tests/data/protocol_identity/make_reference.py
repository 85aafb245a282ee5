"""Writes reference.json: weigh() rows of a few fleet bogies by both protocols (params.yaml as committed).

Run on the code before a change meant to keep results bit-identical (or after one meant to change them), then
tests/pipeline/test_protocol_identity.py checks the code against it. Floats are stored as float.hex() so the
comparison is bit-for-bit. ``python tests/data/protocol_identity/make_reference.py`` from the repository root.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[3]
sys.path.insert(0, str(ROOT / "tests"))

from _fingerprint import fingerprint  # noqa: E402

from bogie.fleet.sampling.sample import bogie_from_sample  # noqa: E402
from bogie.fleet.weighing.weigher import weigh  # noqa: E402
from pipeline.config import load_config  # noqa: E402
from pipeline.sample import sample_fleet  # noqa: E402

#: fleet sample indices (params.yaml): three tandem, three tri-axle
INDICES = (3, 8, 11, 0, 1, 2)


def encode(value):
    if isinstance(value, float):
        return {"hex": value.hex()}
    return value


def main() -> None:
    config = load_config(ROOT / "params.yaml")
    records = sample_fleet(config).to_dict("records")
    out = []
    for index in INDICES:
        record = records[index]
        for protocol in ("static", "wim"):
            row = weigh(bogie_from_sample(record), record, protocol, getattr(config.protocol, protocol))
            out.append({"index": index, "protocol": protocol, "row": {k: encode(v) for k, v in row.items()}})
    commit = subprocess.run(["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True, text=True).stdout.strip()
    path = Path(__file__).with_name("reference.json")
    path.write_text(json.dumps({"commit": commit, "machine": fingerprint(), "rows": out}, indent=1) + "\n")
    print(path, len(out), "rows")


if __name__ == "__main__":
    main()
