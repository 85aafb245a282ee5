"""A package's public names loaded on first use (PEP 562): the one recipe of ``bogie.fleet`` and its rooms.

A package made this way imports nothing when it is imported, so importing one of its modules (the params loader
imports :mod:`bogie.fleet.calibration.settings`) neither loads nor depends on the others; the pipeline's code
dependencies and the simulate stage's code hash follow the static imports (:mod:`pipeline.deps`), so the pipeline
imports each name from the module that defines it, never through such a package (``tests/pipeline/test_dvc_deps.py``).
"""

from __future__ import annotations

import importlib
import importlib.util
from collections.abc import Callable, Mapping
from typing import Any

__all__ = ["lazy_names"]


def lazy_names(
    package: str, exports: Mapping[str, str], former: str | None = None
) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """The module ``__getattr__`` and ``__dir__`` of ``package``: each public name of ``exports`` (name -> the
    submodule defining it, relative to ``package``, or a whole dotted path from ``bogie.``) imported on first
    use; a submodule by its name; and, if the package
    was once a module (issue 42 made ``bogie.fleet.calibration`` a folder), any other name that module had, from
    ``former``, the submodule that holds its code now, so that ``from bogie.fleet.calibration import observed_groups``
    still works."""
    namespace = importlib.import_module(package).__dict__

    def __getattr__(name: str) -> Any:
        if name in exports:
            where = exports[name]
            value = getattr(
                importlib.import_module(where if where.startswith("bogie.") else f"{package}.{where}"), name
            )
        elif not name.startswith("__") and importlib.util.find_spec(f"{package}.{name}") is not None:
            return importlib.import_module(f"{package}.{name}")  # a submodule: the import system binds it
        elif former is not None and not name.startswith("__"):
            module = importlib.import_module(f"{package}.{former}")
            if not hasattr(module, name):
                raise AttributeError(f"module {package!r} has no attribute {name!r}")
            value = getattr(module, name)
        else:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        namespace[name] = value  # the next lookup is a plain one
        return value

    def __dir__() -> list[str]:
        return sorted({*namespace, *exports})

    return __getattr__, __dir__
