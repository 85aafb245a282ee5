"""The DVC pipeline's stage programs: thin wrappers that read params.yaml, call bogie and write outputs."""

# before anything imports numpy, for the report's figures (pipeline/figure_numerics.py); results do not depend on it
from pipeline.figure_numerics import limit_numpy_dispatch as _limit_numpy_dispatch  # noqa: E402

_limit_numpy_dispatch()
