"""The small test fleet of the ``bogie.fleet`` tests (``tests/test_fleet.py``, ``tests/test_fleet_design.py``,
``tests/test_fleet_calibration.py``), declared once: its distributions, presets, axle mix and legal group loads.

Module-level names rather than a fixture, because tests parametrize on them (a changed copy of :data:`DISTS` or
:data:`PRESETS` per case). Take copies (``{**DISTS, ...}``), never change them in place.
"""

import bogie.fleet as bf
from bogie.params import GRAVITY

#: every quantity the fleet samples and its distribution (SI: N m/rad, N m s/rad, m, rad, N, -)
DISTS = {
    "bush_stiffness": bf.LogUniform(1.0, 3000.0), "bush_damping": bf.LogUniform(1.0, 300.0),
    "friction_coefficient": bf.TruncNormal(0.25, 0.12, 0.05, 0.6), "contact_roll_radius": bf.Uniform(0.0, 0.12),
    "tyre_wear": bf.Uniform(0.0, 0.012), "chassis_tilt": bf.Uniform(-0.03, 0.03),
    "payload_fraction": bf.Uniform(0.5, 1.0), "equaliser_arm": bf.Uniform(0.12, 0.28),
    "spring_friction_band": bf.Uniform(0.0, 4000.0), "spring_friction_decay": bf.Uniform(0.002, 0.008),
    "road_class": bf.Choice(("A", "B")),
}  # fmt: skip
#: each axle group's legal load [N]
GROUP_LOAD = {"tandem": 18e3 * GRAVITY, "triaxle": 24e3 * GRAVITY}
#: each axle group's base bogie
PRESETS = {"tandem": "tandem_trrl", "triaxle": "triaxle_stage1"}
#: each axle group's share of the fleet
AXLE_MIX = {"tandem": 0.5, "triaxle": 0.5}


def fleet(**changes) -> bf.Fleet:
    """The test fleet, with ``changes`` to any of :class:`bogie.fleet.Fleet`'s arguments."""
    args = dict(distributions=DISTS, axle_mix=AXLE_MIX, presets=PRESETS, legal_group_load=GROUP_LOAD)
    return bf.Fleet(**{**args, **changes})
