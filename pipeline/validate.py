"""DVC stage ``validate``: params.yaml checked as a whole before any stage that writes results runs.

``python -m pipeline.validate`` reads params.yaml through the schema (:mod:`pipeline.config`: every bad key, every
rule between keys, the bounds on the runs and on the memory the studies imply, against a fixed budget:
:mod:`pipeline.config.rules`) and checks that ``observed.path`` (if given) names a file, all of it at once: one
message, a line per bad key (:func:`pipeline.config.check_params`). Then it writes the validated configuration in SI
units to ``data/config.json``, and nothing if anything is bad. Every other stage depends on that file, so a bad value
stops the pipeline here, and DVC, which deletes a stage's outputs before running it, deletes only this small file: a
failed ``dvc exp run -S fleet.n_bogies=-5`` leaves the samples, the runs and the report in place (see the README for
what DVC itself does to params.yaml and how to recover).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from bogie.fleet.sampling.distributions import Distribution
from pipeline.atomic import atomic_file, run_stage, stage_inputs
from pipeline.config import check_params

__all__ = ["as_json", "main"]


def as_json(value: Any) -> Any:
    """A validated configuration (dataclasses, maps, tuples) as plain JSON values; a distribution gets its ``kind``."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        fields = {f.name: as_json(getattr(value, f.name)) for f in dataclasses.fields(value)}
        # a distribution gets its kind; a section of the configuration (or a protocol's settings) does not
        distribution = isinstance(value, Distribution)
        return {"kind": type(value).__name__.lower(), **fields} if distribution else fields
    if isinstance(value, Mapping):
        return {str(k): as_json(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [as_json(v) for v in value]
    return value


def main(argv: list[str] | None = None) -> int:
    """Run the stage: validate params.yaml and write data/config.json; exit 2 with one line per bad key."""
    parser = argparse.ArgumentParser(prog="python -m pipeline.validate", description=__doc__.splitlines()[0])
    parser.add_argument("--params", default="params.yaml", help="parameter file (default: params.yaml)")
    parser.add_argument("--out", default="data/config.json", help="validated configuration (default: data/config.json)")
    args = parser.parse_args(argv)
    return run_stage("validate", parser, args, lambda own: _stage(args))


def _stage(args: argparse.Namespace) -> int:
    """Validate, write, say so; the exit code (errors: :func:`pipeline.atomic.run_stage`'s)."""
    notes: list[str] = []
    # a wrong observed.path is found now, with the bad keys, not after the simulation (observed checks it again)
    with stage_inputs("validate", prefix=f"{args.params}: "):
        config = check_params(args.params, notes.append)
    with atomic_file(Path(args.out)) as tmp:
        tmp.write_text(json.dumps(as_json(config), indent=1) + "\n", encoding="utf-8")
    print(f"validate: {args.params} is valid; wrote {args.out}")
    for note in notes:
        print(f"validate: {note}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
