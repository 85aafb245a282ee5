"""The fast paths of a weighing's set-up (issue 15) give exactly what the general code gives."""

from __future__ import annotations

import numpy as np
import pytest

from bogie.params import Bogie, equaliser_arm_changes, with_equaliser_arms
from bogie.presets import preset, preset_fields
from bogie.steel import nonlinear as nl
from bogie.steel.force import pack


@pytest.mark.parametrize("name", ["tandem_trrl", "triaxle_stage1"])
def test_relaxed_pack_and_drive_row(name):
    bogie = preset(name, chassis_tilt=0.01)
    relaxed = nl.pack(bogie.replace(friction_coefficient=0.0, spring_friction_band=0.0))
    mass, data_f, data_i = nl.cached_pack(bogie)
    data_f[nl.FRICTION_SLOTS] = 0.0
    assert data_f.tobytes() == relaxed[1].tobytes() and np.array_equal(data_i, relaxed[2])
    assert nl.cached_pack(bogie)[1].tobytes() == nl.pack(bogie)[1].tobytes()  # the cached copy was not changed
    t = np.arange(50) * 0.01
    inputs = nl.Inputs(0.01, np.sin(t)[:, None] * np.ones(bogie.n_axles), np.cos(t)[:, None] * np.ones(bogie.n_axles),
                       0.5 + 0.1 * t, 0.002 * t)  # fmt: skip
    drive = inputs.drive(bogie)
    for row in (0, 7, -1):
        assert inputs.drive_row(bogie, row).tobytes() == drive[row].tobytes()


@pytest.mark.parametrize("name", ["tandem_trrl", "triaxle_stage1"])
def test_one_validation_builds_the_stepwise_bogie(name):
    changes = dict(bush_stiffness=800.0, friction_coefficient=0.2, chassis_tilt=-0.01, payload_mass=6000.0)
    stepwise = with_equaliser_arms(preset(name, **changes), 0.2)
    fields = preset_fields(name)
    fields.update(changes)
    fields.update(equaliser_arm_changes(fields, 0.2))
    once = Bogie(**fields)
    assert repr(once) == repr(stepwise)
    assert preset_fields(name) == {f: getattr(preset(name), f) for f in fields}  # the cached preset is untouched


def test_iso8608_profile_heights_are_np_interp_bit_for_bit():
    from bogie.road import ISO8608Profile

    rng = np.random.default_rng(3)
    for seed in range(20):
        profile = ISO8608Profile("C", length=float(rng.uniform(50.0, 120.0)), seed=seed)
        x = rng.uniform(-30.0, 2.0 * profile.length, (int(rng.integers(1, 4000)), 3))
        grid_x, _ = profile._interpolation_grid()
        x[0, :] = grid_x[rng.integers(0, len(grid_x), 3)]  # on grid points
        x[1, :] = (0.0, -0.0, profile.length)
        for points in (x, np.clip(x, 0.0, profile.length), np.clip(x, 0.0, 0.99 * profile.length)):
            expected = np.interp(np.mod(points, profile.length), grid_x, profile._grid_h)
            assert profile(points).tobytes() == expected.tobytes()


def test_iso8608_grid_heights_are_the_profiles_own_at_the_grid_points():
    from bogie.road import ISO8608Profile

    profile = ISO8608Profile("B", length=50.0, seed=4)
    dx = profile.grid_spacing
    k = np.arange(-40, 3 * 16384 // 2)
    # every index, wrapped into the period, is the height a call gives at that grid point (also past the period)
    assert np.array_equal(profile.grid_heights(int(k[0]), int(k[-1])), profile(np.mod(k, 16384) * dx))
    for k_from, k_to in ((-40, 1000), (0, 16384), (5, 9), (-16384, 16384)):  # two slices, one, and the full period
        k = np.arange(k_from, k_to + 1)
        assert np.array_equal(profile.grid_heights(k_from, k_to), profile(np.mod(k, 16384) * dx))
    assert dx == 50.0 / 16384


def test_one_cache_of_a_bogies_pack_serves_the_equilibrium_and_the_phases():
    """issue 29: nonlinear and phases kept one id()-keyed cache each of the same pack; now nl.constants is the one."""
    from bogie.steel import phases

    assert not hasattr(phases, "_CONSTANTS") and not hasattr(nl, "_PACKED")
    bogie = preset("tandem_trrl", chassis_tilt=0.01)
    c = nl.constants(bogie)
    assert nl.constants(bogie) is c
    assert pack._CONSTANTS[id(bogie)][0] is bogie  # the entry holds its bogie: its id() cannot pass to another object
    mass, data_f, data_i = nl.cached_pack(bogie)
    packed = nl.pack(bogie)
    assert data_f.tobytes() == c.data_f.tobytes() == packed[1].tobytes() and data_f is not c.data_f
    assert np.array_equal(mass, packed[0]) and np.array_equal(data_i, packed[2])
    data_f[:] = 0.0
    assert nl.constants(bogie).data_f.tobytes() == packed[1].tobytes()  # the equilibrium's copy, not the cache
    levers = pack._levers(bogie)
    assert c.r_tol.tobytes() == nl.residual_tolerance(bogie).tobytes() == nl.residual_tolerance(bogie, levers).tobytes()
    assert c.u_limit.tobytes() == nl.limits(bogie).tobytes()
    twin = preset("tandem_trrl", chassis_tilt=0.01)  # equal, another object: an entry of its own, never by equality
    assert twin == bogie and nl.constants(twin) is not c
