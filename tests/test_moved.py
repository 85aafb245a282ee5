"""The steel model's old module paths (issue 42 moved them into bogie.steel) work for one release, with a warning."""

import subprocess
import sys
from pathlib import Path

from bogie._moved import MOVED

ROOT = Path(__file__).resolve().parent.parent


def test_an_old_path_is_the_new_module_and_warns_naming_its_new_home():
    code = """
import sys, warnings
import bogie
import bogie.steel.nonlinear as new
with warnings.catch_warnings(record=True) as caught:
    warnings.simplefilter("always")
    from bogie.nonlinear import simulate
    import bogie.static
    from bogie import phases
assert simulate is new.simulate
assert sys.modules["bogie.nonlinear"] is new
assert bogie.static is sys.modules["bogie.steel.static"]
assert phases is sys.modules["bogie.steel.phases"]
import bogie.fe.frame, bogie.steel.fe.frame  # a module inside a moved package: the one module, not a second copy
assert sys.modules["bogie.fe.frame"] is sys.modules["bogie.steel.fe.frame"]
messages = [str(w.message) for w in caught if w.category is DeprecationWarning]
assert any(m.startswith("bogie.nonlinear moved to bogie.steel.nonlinear") for m in messages), messages
assert any(m.startswith("bogie.static moved to bogie.steel.static") for m in messages), messages
print("ok")
"""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "ok"


def test_every_moved_path_has_a_new_module_and_no_file_left_at_the_old_one():
    for old, new in MOVED.items():
        old_file = ROOT.joinpath(*old.split("."))
        assert not old_file.with_suffix(".py").exists() and not (old_file / "__init__.py").exists(), old
        new_file = ROOT.joinpath(*new.split("."))
        assert new_file.with_suffix(".py").is_file() or (new_file / "__init__.py").is_file(), new


def test_an_unknown_module_of_bogie_is_still_an_import_error():
    import importlib

    import pytest

    with pytest.raises(ModuleNotFoundError):
        importlib.import_module("bogie.no_such_module")


def test_the_fleet_rooms_keep_their_former_modules_names_and_the_flat_paths_warn():
    code = """
import warnings
with warnings.catch_warnings(record=True) as caught:
    warnings.simplefilter("always")
    from bogie.fleet.calibration_fit import calibrate
    from bogie.fleet.calibration import observed_groups, calibrate as calibrate2
    from bogie.fleet.sampling import sample_fleet, road_seed
    from bogie.fleet.design import study_designs, FACTORS
    from bogie.fleet.weighing import weigh_fleet, Protocols
from bogie.fleet.calibration.fitting import calibrate as new
from bogie.fleet.calibration.problem import observed_groups as groups
from bogie.fleet.sampling.sample import sample_fleet as sample
from bogie.fleet.design.experiment import FACTORS as factors
from bogie.fleet.weighing.weigher import Protocols as protocols
assert calibrate is new and calibrate2 is new and observed_groups is groups and sample_fleet is sample
assert FACTORS is factors and Protocols is protocols
messages = [str(w.message) for w in caught if w.category is DeprecationWarning]
assert messages == ["bogie.fleet.calibration_fit moved to bogie.fleet.calibration.fitting (issue 42); the old path "
                    "works until the next release"], messages
import bogie.fleet.calibration as room
try:
    room.no_such_name
except AttributeError as error:
    assert "no_such_name" in str(error)
else:
    raise AssertionError("a missing name was found")
print("ok")
"""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "ok"
