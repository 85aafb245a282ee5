"""Modules that moved, found at their old paths for one release with a DeprecationWarning naming the new home.

Issue 42 moved the steel model's modules into :mod:`bogie.steel` and grouped :mod:`bogie.fleet` by concern
(``docs/architecture.md``). ``import bogie.static``
or ``from bogie.nonlinear import simulate`` still works: :class:`MovedFinder`, installed by ``import bogie``, imports
the new module, warns once per old path, and binds the old name to the very same module object (so a patch applied
through either name is seen through both). Remove an entry, or the whole table, at the next release.
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.machinery
import sys
import warnings
from types import ModuleType

#: old dotted path -> new dotted path
MOVED: dict[str, str] = {
    "bogie.static": "bogie.steel.static",
    "bogie.linear": "bogie.steel.linear",
    "bogie.fe": "bogie.steel.fe",
    "bogie.frame": "bogie.steel.fe.frame",
    "bogie.cases": "bogie.steel.cases",
    "bogie.nonlinear": "bogie.steel.nonlinear",
    "bogie.newmark": "bogie.steel.newmark",
    "bogie.phases": "bogie.steel.phases",
    # bogie.fleet grouped by concern; bogie.fleet.sampling, .weighing, .calibration and .design are rooms now, their
    # former modules' names still found there (bogie.lazy)
    **{f"bogie.fleet.{old}": f"bogie.fleet.{new}" for old, new in (
        ("distributions", "sampling.distributions"), ("seeds", "sampling.seeds"), ("tilted", "sampling.tilted"),
        ("protocol_settings", "weighing.settings"), ("protocols", "weighing.protocols"), ("runs", "weighing.runs"),
        ("survey", "weighing.survey"), ("observed", "weighing.observed"),
        ("calibration_settings", "calibration.settings"), ("calibration_table", "calibration.table"),
        ("calibration_fit", "calibration.fitting"), ("calibration_posterior", "calibration.posterior"),
        ("priors", "calibration.priors"), ("calibration_attribution", "calibration.attribution"),
        ("calibration_checks", "calibration.checks"), ("design_settings", "design.settings"),
        ("design_analysis", "design.analysis"), ("design_table", "design.table"),
    )},
}  # fmt: skip


class _AliasLoader(importlib.abc.Loader):
    """Loads an old path as the module at its new one."""

    def __init__(self, new: str) -> None:
        self.new = new

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> ModuleType:
        return ModuleType(spec.name)  # a placeholder: exec_module puts the real module in its place

    def exec_module(self, module: ModuleType) -> None:
        old = module.__name__
        warnings.warn(
            f"{old} moved to {self.new} (issue 42); the old path works until the next release",
            DeprecationWarning,
            stacklevel=2,
        )
        # the import system returns whatever sys.modules holds under the old name once this returns
        sys.modules[old] = importlib.import_module(self.new)


class MovedFinder(importlib.abc.MetaPathFinder):
    """Finds the old paths of :data:`MOVED` and of the modules inside them, and nothing else."""

    def find_spec(self, fullname: str, path: object, target: object = None) -> importlib.machinery.ModuleSpec | None:
        new = moved_to(fullname)
        if new is None:
            return None
        return importlib.machinery.ModuleSpec(fullname, _AliasLoader(new))


def moved_to(fullname: str) -> str | None:
    """The new path of ``fullname``: a moved module's, or a module inside a moved package (``bogie.fe.frame`` is
    ``bogie.steel.fe.frame``, never a second copy of its file); None if it did not move."""
    if fullname in MOVED:
        return MOVED[fullname]
    for old, new in MOVED.items():
        if fullname.startswith(old + "."):
            return new + fullname[len(old) :]
    return None


def install() -> None:
    """Put :class:`MovedFinder` first on ``sys.meta_path``, once. First: an old package's ``__path__`` is the new
    folder, so the standard finder would load ``bogie.fe.frame`` from it as a second copy of ``bogie.steel.fe.frame``.
    It answers for the old paths only, and no file is left at one (``tests/test_moved.py``)."""
    if not any(isinstance(finder, MovedFinder) for finder in sys.meta_path):
        sys.meta_path.insert(0, MovedFinder())
