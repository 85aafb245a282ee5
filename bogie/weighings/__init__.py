"""Observed axle weighings: readers of WIM and weighbridge records, axle groups, and the survey statistics.

``readers`` reads the documented CSV layout and the fixed-width WIM exchange formats MON, CASTOR, BeDIT and DITIS
(layouts in ``docs/weighings.md``) into one vehicle table, SI units; ``groups`` splits vehicles into axle groups
and filters them; ``stats`` computes the survey statistics with the report's definitions, the same function the
survey stage applies to the simulated fleet; ``survey.observed_survey`` does all three for one file (what
``bogie weighings`` prints). numpy and pandas only; no pipeline import. This file imports nothing, so that the
survey stage, which imports ``stats``, does not depend on the readers.
"""
