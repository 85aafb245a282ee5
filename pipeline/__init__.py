"""The DVC pipeline's stage programs: thin wrappers that read params.yaml, call bogie and write outputs."""

# before anything imports numpy or numba: the same bits on every x86-64 machine (pipeline/portable.py)
from pipeline.portable import pin as _pin  # noqa: E402

_pin()
