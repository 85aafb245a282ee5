"""The library's one argument check and its one message (bogie.settings; issue 42 Must 2), pinned by hand-worked cases:
each message below is written out from the form in bogie/settings.py's docstring, not copied from a run."""

import argparse
import math

import numpy as np
import pytest

from bogie.ranges import check_positive, check_scalar
from bogie.settings import Setting, check_value, refusal


def _message(call) -> str:
    with pytest.raises(Exception) as err:
        call()
    return err.value.args[0]


@pytest.mark.parametrize(
    ("call", "message"),
    [
        # a float out of a closed range: the name, the value, the range, the unit bare
        (lambda: check_value("tyre_wear", 0.07, "m", low=0.0, high=0.05),
         "tyre_wear = 0.07 is out of range: must be in [0, 0.05] m"),
        # an open bound: a parenthesis in a range, > alone
        (lambda: check_value("beta", 0.0, low=0.0, low_open=True, high=0.5),
         "beta = 0.0 is out of range: must be in (0, 0.5] -"),
        (lambda: check_value("dt", -0.1, "s", low=0.0, low_open=True), "dt = -0.1 is out of range: must be > 0 s"),
        (lambda: check_value("x", 1.0, "m", high=1.0, high_open=True), "x = 1.0 is out of range: must be < 1 m"),
        # not finite: out of range too
        (lambda: check_value("payload_mass", math.nan, "kg", low=0.0, low_open=True, high=1e6),
         "payload_mass = nan is out of range: must be in (0, 1e+06] kg"),
        # a whole number: given a float (even with no fraction), given too few
        (lambda: check_value("seed", 3.0, low=0, whole=True),
         "seed = 3.0 is not a whole number (float): must be a whole number >= 0 -"),
        (lambda: check_value("n_jobs", 0, low=1, high=8, whole=True),
         "n_jobs = 0 is out of range: must be a whole number in [1, 8] -"),
        # the wrong kind: a bool (numpy's too), a text, a list where a number is wanted
        (lambda: check_value("bush_stiffness", True, "N m/rad", low=0.0, high=1e7),
         "bush_stiffness = True is not a number (bool): must be in [0, 1e+07] N m/rad"),
        (lambda: check_value("bush_stiffness", np.bool_(False), "N m/rad", low=0.0, high=1e7),
         "bush_stiffness = False is not a number (bool): must be in [0, 1e+07] N m/rad"),
        (lambda: check_value("tyre_damping", "soft", "N s/m", low=0.0, high=1e7),
         "tyre_damping = 'soft' is not a number (text): must be in [0, 1e+07] N s/m"),
        (lambda: check_value("speed", [1.0], "m/s", low=0.0), "speed = [1.0] is not a number (list): must be >= 0 m/s"),
        # a numpy scalar as the user wrote it, not np.float64(0.001)
        (lambda: check_value("x", np.float64(0.001), "m", low=0.01, high=1.0),
         "x = 0.001 is out of range: must be in [0.01, 1] m"),
        (lambda: check_value("k", np.int64(-2), low=0, whole=True),
         "k = -2 is out of range: must be a whole number >= 0 -"),
        # a note last, in parentheses
        (lambda: check_value("beta", 0.7, low=0.0, low_open=True, high=0.5, note="Newmark parameter"),
         "beta = 0.7 is out of range: must be in (0, 0.5] - (Newmark parameter)"),
        # None allowed: said after the unit
        (lambda: check_value("resolution_kg", -1, "kg", low=0.0, low_open=True, high=1000.0, optional=True),
         "resolution_kg = -1 is out of range: must be in (0, 1000] kg, or None"),
        # a name among choices
        (lambda: Setting("-", "", choices=("none", "quartz")).check("sensor", "Quartz"),
         "sensor = 'Quartz' is unknown: must be one of none, quartz"),
        # the bogie's range table's checks go through the same message
        (lambda: check_scalar("tyre_radius", 5.0, 0.05, 2.0, "m", True),
         "tyre_radius = 5.0 is out of range: must be in [0.05, 2] m"),
        (lambda: check_scalar("equaliser_stop", 0, 0.0, math.pi, "rad", False),
         "equaliser_stop = 0 is out of range: must be in (0, 3.14159] rad"),
        (lambda: check_scalar("tyre_damping", "1000", 0.0, 1e7, "N s/m", True),
         "tyre_damping = '1000' is not a number (text): must be in [0, 1e+07] N s/m"),
        (lambda: check_positive("tolerance", -1e-7, "m"), "tolerance = -1e-07 is out of range: must be > 0 m"),
        (lambda: check_positive("speed", -1.0, "m/s", allow_zero=True),
         "speed = -1.0 is out of range: must be >= 0 m/s"),
    ],
)  # fmt: skip
def test_one_message_form(call, message):
    assert _message(call) == message


def test_the_error_is_the_callers_and_the_message_the_same():
    with pytest.raises(argparse.ArgumentTypeError) as err:
        check_value("--tilt-deg", 30.0, "degree", low=-10.0, high=10.0, error=argparse.ArgumentTypeError)
    assert str(err.value) == "--tilt-deg = 30.0 is out of range: must be in [-10, 10] degree"
    with pytest.raises(KeyError) as key_err:
        Setting("m", "", low=0.0).check("Demo.spare", -1.0, KeyError, note="a spare length")
    assert key_err.value.args[0] == "Demo.spare = -1.0 is out of range: must be >= 0 m (a spare length)"


def test_refusal_is_the_text_check_value_raises():
    kwargs = {"low": 0.0, "low_open": True, "high": 2.0, "note": "fraction of the design payload"}
    text = "load_factor = 2.5 is out of range: must be in (0, 2] - (fraction of the design payload)"
    assert refusal("load_factor", 2.5, "-", **kwargs) == text
    assert _message(lambda: check_value("load_factor", 2.5, "-", **kwargs)) == text


def test_an_allowed_value_is_returned_as_the_library_takes_it():
    assert check_value("x", 1, "m", low=0.0) == 1.0 and type(check_value("x", 1, "m", low=0.0)) is float
    assert check_value("x", np.float32(0.5), "m", low=0.0) == float(np.float32(0.5))
    assert check_value("x", np.array(0.25), "m", low=0.0) == 0.25  # a 0-d array is a number
    assert check_value("n", np.int64(3), low=2, whole=True) == 3 and type(check_value("n", 3, whole=True)) is int
    assert check_value("resolution_kg", None, "kg", low=0.0, optional=True) is None
    # the declared bounds themselves
    assert check_value("x", 0.5, low=0.0, high=0.5) == 0.5
    assert check_value("x", 0.0, low=0.0, high=0.5, high_open=True) == 0.0


def test_check_scalar_returns_the_float_it_was_given():
    value = 0.5
    assert check_scalar("x", value, 0.0, 1.0, "m", True) is value  # the fast path: the same object, unconverted
    assert check_scalar("x", np.float64(0.5), 0.0, 1.0, "m", True) == 0.5
    assert type(check_scalar("x", 1, 0.0, 1.0, "m", True)) is float
