"""The named presets of :class:`bogie.params.Bogie`: the reference's tandem and tri-axle, their shared fields and the
provenance constants behind them (each one's source in ``docs/presets.md``).

:mod:`bogie.params` holds the bogie itself, its ranges and validation, and re-exports every name here, so
``from bogie.params import preset`` keeps working; the presets' stop and friction-decay values stay there, being
:class:`~bogie.params.Bogie`'s defaults too (``PRESET_EQUALISER_STOP``, ``PRESET_EQUALISER_STOP_STIFFNESS``,
``PRESET_SPRING_FRICTION_DECAY``).
"""

from __future__ import annotations

import dataclasses
import functools
import types
from collections.abc import Mapping
from typing import Any

from bogie.params import (
    GRAVITY,
    PRESET_EQUALISER_STOP,
    PRESET_EQUALISER_STOP_STIFFNESS,
    PRESET_SPRING_FRICTION_DECAY,
    Bogie,
)

__all__ = [
    "PRESETS",
    "PRESET_EQUALISER_ARM",
    "PRESET_PAYLOAD_CG_X",
    "PRESET_RADIUS_OF_GYRATION",
    "PRESET_SHARED",
    "PRESET_SPRING_FRICTION_BAND",
    "PRESET_SPRING_HALF_LENGTH",
    "STAGE1_CHASSIS_DEFLECTION",
    "preset",
    "preset_fields",
    "tandem_trrl",
    "triaxle_stage1",
]

#: the presets' interleaf friction band of a multi-leaf trailer spring: half the width of its load-deflection
#: loop, about a tenth of the springs' 19-25 kN design load (``docs/presets.md``, "Leaf-spring hysteresis") [N]
PRESET_SPRING_FRICTION_BAND = 2000.0
#: the reference's Stage 1 chassis downward displacement alpha [m] (Figure 2)
STAGE1_CHASSIS_DEFLECTION = 0.057
#: the presets' spring half-length: a 1.0 m slipper spring (``docs/presets.md``) [m]
PRESET_SPRING_HALF_LENGTH = 0.5
#: the presets' equaliser arm, front and rear: closes the chain 0.5 + 0.155 + 0.155 + 0.5 = 1.31 m [m]
PRESET_EQUALISER_ARM = 0.155
#: the presets' payload CG behind the king pin: a uniformly loaded 12 m trailer [m]
PRESET_PAYLOAD_CG_X = 4.8
#: the presets' chassis radius of gyration about the payload CG: L / sqrt(12) of a 12 m trailer [m]
PRESET_RADIUS_OF_GYRATION = 3.5
#: every field the two presets share, written once (provenance of each in ``docs/presets.md``); a preset adds its
#: axle positions, its payload and its bush stiffness (:func:`_preset`), the per-axle fields follow its axle count
PRESET_SHARED: Mapping[str, Any] = types.MappingProxyType(
    {
        "road_spring_stiffness": 0.6e6,
        "tyre_stiffness": 1.6e6,
        "tyre_damping": 2.0e3,
        "tyre_radius": 0.5,
        "axle_mass": 300.0,
        "equaliser_inertia": 0.2,
        "payload_cg_x": PRESET_PAYLOAD_CG_X,
        "equaliser_front_tip_drop": 0.0,
        "equaliser_rear_tip_drop": 0.0,
        "spring_length_rate": 0.3,
        "spring_end_slope_rate": 2.0,
        "contact_tangential_stiffness": 5e6,
        "bush_damping": 0.0,
        "contact_roll_radius": 0.075,
        "friction_coefficient": 0.3,
        "equaliser_stop": PRESET_EQUALISER_STOP,
        "equaliser_stop_stiffness": PRESET_EQUALISER_STOP_STIFFNESS,
        "spring_friction_band": PRESET_SPRING_FRICTION_BAND,
        "spring_friction_decay": PRESET_SPRING_FRICTION_DECAY,
    }
)


def _preset(axle_x: tuple[float, ...], payload_mass: float, bush_stiffness: float, changes: dict[str, Any]) -> Bogie:
    """A preset: :data:`PRESET_SHARED`, a spring per axle and an equaliser between each two, the given axles,
    payload (its pitch inertia about the king pin: ``m (x_cg^2 + r_g^2)``) and bush stiffness; then ``changes``."""
    n = len(axle_x)
    base = Bogie(
        axle_x=axle_x,
        spring_front_half_length=(PRESET_SPRING_HALF_LENGTH,) * n,
        spring_rear_half_length=(PRESET_SPRING_HALF_LENGTH,) * n,
        equaliser_front_arm=(PRESET_EQUALISER_ARM,) * (n - 1),
        equaliser_rear_arm=(PRESET_EQUALISER_ARM,) * (n - 1),
        payload_mass=payload_mass,
        chassis_pitch_inertia=payload_mass * (PRESET_PAYLOAD_CG_X**2 + PRESET_RADIUS_OF_GYRATION**2),
        bush_stiffness=bush_stiffness,
        **PRESET_SHARED,
    )
    return base.replace(**changes) if changes else base


def tandem_trrl(**changes: Any) -> Bogie:
    """The two-axle suspension of the reference's Stages 3 and 4 (one side); provenance in ``docs/presets.md``.

    The reference's 6500 kg payload and its "high" bush stiffness, 1000 N m/rad; the rest is :data:`PRESET_SHARED`.
    """
    return _preset((7.345, 8.655), payload_mass=6500.0, bush_stiffness=1000.0, changes=changes)


def triaxle_stage1(**changes: Any) -> Bogie:
    """The tri-axle suspension of the reference's Stages 1 and 2 (one side), with q = 4.3.

    Same springs, tyres and arms as :func:`tandem_trrl` (:data:`PRESET_SHARED`); the bush stiffness is chosen so that
    q = b^2 K_S / (4 K_B) = 4.3, the value the reference gives for its Stage 1 suspension, and the payload so that
    the design load deflects spring and tyre by the reference's alpha = 57 mm.
    """
    b = PRESET_EQUALISER_ARM
    k_s = 1.0 / (1.0 / PRESET_SHARED["tyre_stiffness"] + 1.0 / PRESET_SHARED["road_spring_stiffness"])
    # the reference's chassis deflection alpha = 57 mm under the design load: 3 K_S alpha x_b = m g x_cg
    payload = 3.0 * k_s * STAGE1_CHASSIS_DEFLECTION * 8.0 / (GRAVITY * PRESET_PAYLOAD_CG_X)
    return _preset((6.69, 8.0, 9.31), payload_mass=payload, bush_stiffness=b * b * k_s / (4.0 * 4.3), changes=changes)


PRESETS = {"tandem_trrl": tandem_trrl, "triaxle_stage1": triaxle_stage1}


@functools.cache
def _preset_base(name: str) -> Bogie:
    return preset(name)


def preset_fields(name: str) -> dict[str, Any]:
    """The fields of the named preset (:func:`preset`, validated once per process and name) as a new dict: change
    some and build one :class:`Bogie` from it instead of validating a preset and then each changed copy."""
    base = _preset_base(name)
    return {f.name: getattr(base, f.name) for f in dataclasses.fields(Bogie)}


def preset(name: str, **changes: Any) -> Bogie:
    """A named preset (``tandem_trrl`` or ``triaxle_stage1``) with optional field changes."""
    try:
        factory = PRESETS[name]
    except KeyError:
        raise ValueError(f"unknown preset {name!r}: must be one of {', '.join(PRESETS)}") from None
    return factory(**changes)
