"""The group filter's settings, declared once (:mod:`bogie.settings`): what :func:`bogie.weighings.groups.axle_groups`
and :func:`~bogie.weighings.groups.filter_groups` check their arguments with, and what params.yaml's ``observed:``
keys are made from (``pipeline/config/schema.py``). A light module of its own, so that params.yaml's loader, which
every stage imports, does not import the readers or their compiled kernels.
"""

from __future__ import annotations

from bogie.settings import Setting

__all__ = ["GROUP_FILTER", "MAX_RESOLUTION_KG", "POSITIONS", "WEIGHT_STEPS_KG"]

#: group positions a filter can ask for: every group, or the steer, drive or trailer groups (bogie.weighings.groups)
POSITIONS: tuple[str, ...] = ("all", "steer", "drive", "trailer")
#: the weight steps a file's resolution is detected among [kg] (MON files are seen at 10 kg and at 100 kg; CASTOR,
#: BeDIT, DITIS and TMG 2001 write kg/100; bogie.weighings.resolution)
WEIGHT_STEPS_KG: tuple[int, ...] = (1, 2, 5, 10, 20, 50, 100, 200, 500, 1000)
#: the largest weight resolution a user may set [kg]: the coarsest step detected
MAX_RESOLUTION_KG: float = float(WEIGHT_STEPS_KG[-1])

#: the group filter's settings by name (the library's argument is the name with its unit's suffix: ``min_group_load``
#: is ``filter_groups``' ``min_group_load_kg``)
GROUP_FILTER: dict[str, Setting] = {
    "min_group_load": Setting(
        "kg", "Smallest group load kept, observed and simulated groups alike (a mass, as the weighings give it): laden "
        "groups only (e.g. 15 000 kg for tri-axles).", low=0.0, high=100_000.0,
    ),
    "group_spacing": Setting("m", "Largest spacing of two axles of one observed group.", low=0.0, low_open=True,
                             high=5.0),
    "position": Setting("-", "Group position kept: all, steer, drive or trailer.", choices=POSITIONS),
    "resolution_kg": Setting(
        "kg", "The file's weight resolution, applied to the simulated readings (a whole multiple of the format's "
        "weight unit); None: detected from the file's loads.", low=0.0, low_open=True, high=MAX_RESOLUTION_KG,
        optional=True,
    ),
}  # fmt: skip
