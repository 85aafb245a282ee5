"""A digest of how this process computes: two processes with the same digest give the same bits in bogie.

What can make the last bits of a result differ between two processes (``docs/architecture.md``, "The same bits on
every machine") is the C library's elementary functions, which :mod:`bogie.numerics` calls, and the arithmetic of the
compiled kernels (the CPU numba compiles for, the fused multiply-adds it contracts, numba's and LLVM's versions).
:func:`numerics_digest` computes a little of each and hashes every bit: the simulate stage records it in every part
file and refuses a worker whose digest is not its own, and :mod:`pipeline.portable` compares it with the digest of the
machines that made the committed results.
"""

from __future__ import annotations

import functools
import hashlib
import math

import numpy as np

from bogie import numerics
from bogie.presets import triaxle_stage1
from bogie.steel import phases

__all__ = ["numerics_digest"]

#: arguments of the digest's elementary functions: ordinary ones and ones near the hard cases of each
_DIGEST_ARGS = (0.1, 0.5, 0.7853981633974483, 1.0, 1.5707963267948966, 2.302585092994046, 3.0, 7.5, 33.0, 1e-7,
                1.0000000000000002, 709.0, 1e5)  # fmt: skip


@functools.lru_cache(maxsize=1)
def numerics_digest() -> str:
    """A short hex digest of results whose last bits depend on how this process computes.

    :mod:`bogie.numerics`'s elementary functions on fixed arguments, and a short weighing by the compiled kernels
    (:func:`bogie.steel.phases.run`: the Stage 1 tri-axle tilted nose up, its payload ramped on, then crawling over a
    wavy road with adaptive steps, where spring-end friction and rolling contacts act). Two processes with the same
    digest compute the same bits in bogie; with different digests (another C library, another compile target, another
    architecture) their results may differ in the last bits. About 2 ms once the kernels are compiled, once a
    process."""
    digest = hashlib.sha256()
    args = np.array(_DIGEST_ARGS)
    functions = (
        numerics.exp(-args / 10.0), numerics.log(args), numerics.sin(args), numerics.cos(args),
        numerics.power(args, 1.0 / 3.0), numerics.arctan2(args, 0.3),
    )  # fmt: skip
    for values in functions:
        digest.update(np.ascontiguousarray(values).tobytes())
    bogie = triaxle_stage1().replace(
        chassis_tilt=math.radians(0.7), friction_coefficient=0.3, contact_roll_radius=0.06, spring_friction_band=2000.0
    )
    dx = 0.01
    x = np.arange(600) * dx
    heights = 0.004 * numerics.sin(x * (2.0 * math.pi / 0.9)) * numerics.cos(x * (2.0 * math.pi / 3.1))
    weighing = [
        phases.Phase(0.3, (0.3, 1.0), dt=0.001, name="ramp"),
        phases.Phase(1.5, 1.0, road=phases.RoadTable(-3.0, dx, heights), speed=1.4, dt=0.001, tolerance=2e-7,
                     name="crawl"),
    ]  # fmt: skip
    result = phases.run(bogie, weighing)
    if not result.success:  # a kernel that cannot run this is itself a difference worth a digest of its own
        digest.update(result.message.encode())
    else:
        state = result.final_state
        for values in (state.u, state.v, state.history):
            digest.update(np.ascontiguousarray(values).tobytes())
    return digest.hexdigest()[:16]
