"""Thrusters: the derived allocation matrix, the bounded least-squares allocation, the dynamics.

Reference values are written here from the public figures (the BlueROV2 Heavy's geometry in ROS
FLU axes, the public allocation table's force rows, the T200 data and power fit), not read from
the module under test.
"""

import math

import numpy as np
import pytest
from scipy.optimize import lsq_linear

from uvms_qp.dynamics import (
    AllocationRankError,
    ThrustAllocator,
    Thruster,
    ThrusterDynamics,
    ThrusterLayout,
)
from uvms_qp.errors import ConfigError, InputError, ModelFileError, NonFiniteError, ShapeError

S = math.sqrt(0.5)

# BlueROV2 Heavy, ROS FLU body axes (x forward, y left, z up): positions [m] and the direction a
# positive command pushes the vehicle, thrusters 1-8.
HEAVY_FLU_POSITIONS = [
    (0.14, -0.092, 0.0), (0.14, 0.092, 0.0), (-0.15, -0.092, 0.0), (-0.15, 0.092, 0.0),
    (0.118, -0.215, 0.064), (0.118, 0.215, 0.064), (-0.118, -0.215, 0.064),
    (-0.118, 0.215, 0.064),
]
HEAVY_FLU_AXES = [(-S, -S, 0), (-S, S, 0), (S, -S, 0), (S, S, 0)] + [(0, 0, -1)] * 4

# Force rows of the allocation table used by public controllers (FRD body axes).
PUBLIC_FORCE_ROWS = np.array([
    [-0.707, -0.707, 0.707, 0.707, 0, 0, 0, 0],
    [0.707, -0.707, 0.707, -0.707, 0, 0, 0, 0],
    [0, 0, 0, 0, 1, 1, 1, 1],
])

# T200 published maxima [N] (forward, reverse) and zero-thrust bands [us] by voltage
T200 = {12.0: (36.4, 28.6, 1464, 1536), 16.0: (51.5, 39.9, 1472, 1528),
        20.0: (65.9, 49.4, 1476, 1528)}


def flu_to_frd(v):
    x, y, z = v
    return np.array([x, -y, -z], dtype=float)


def moment(r, a):
    """r x a, written out component by component."""
    return np.array([r[1] * a[2] - r[2] * a[1], r[2] * a[0] - r[0] * a[2],
                     r[0] * a[1] - r[1] * a[0]])


@pytest.fixture(scope="module")
def heavy():
    return ThrusterLayout.bluerov2_heavy()


@pytest.fixture(scope="module")
def allocator(heavy):
    return ThrustAllocator(heavy)


# --- the allocation matrix --------------------------------------------------------------------


def test_heavy_force_rows_equal_the_public_table(heavy):
    np.testing.assert_allclose(heavy.matrix[:3], PUBLIC_FORCE_ROWS, atol=5e-4)


def test_heavy_moment_rows_are_position_cross_axis_in_frd(heavy):
    for i, (r, a) in enumerate(zip(HEAVY_FLU_POSITIONS, HEAVY_FLU_AXES, strict=True)):
        r_frd, a_frd = flu_to_frd(r), flu_to_frd(a)
        np.testing.assert_allclose(heavy.matrix[3:, i], moment(r_frd, a_frd), atol=1e-12)
    # spot values: vertical t5 (front right) pushes down at y = +0.215 m (FRD, right), x = 0.118
    np.testing.assert_allclose(heavy.matrix[3:, 4], [0.215, -0.118, 0.0], atol=1e-12)
    # horizontal t1 (front right, axis back-right): yaw arm 0.7071 (0.14 + 0.092)
    assert heavy.matrix[5, 0] == pytest.approx(S * (0.14 + 0.092))


def test_heavy_actuates_all_six_dofs(heavy):
    assert np.linalg.matrix_rank(heavy.matrix) == 6
    assert heavy.actuated == ("u", "v", "w", "p", "q", "r")
    assert not heavy.matrix.flags.writeable


@pytest.mark.parametrize("voltage", sorted(T200))
def test_heavy_limits_and_dead_band_follow_the_t200_data(voltage):
    forward, reverse, band_low, band_high = T200[voltage]
    layout = ThrusterLayout.bluerov2_heavy(voltage)
    np.testing.assert_array_equal(layout.upper, np.full(8, forward))
    np.testing.assert_array_equal(layout.lower, np.full(8, -reverse))
    t = layout.thrusters[0]
    # linear PWM map: 1500 us stop, 1900 us full forward, 1100 us full reverse
    assert t.forward_dead_band == pytest.approx((band_high - 1500) / 400 * forward)
    assert t.reverse_dead_band == pytest.approx((1500 - band_low) / 400 * reverse)
    assert layout.supply_voltage == voltage  # what a run records as its supply


def test_unknown_voltage_lists_the_published_ones():
    with pytest.raises(InputError, match=r"14\.8 V \(known: 12, 16, 20 V\)"):
        ThrusterLayout.bluerov2_heavy(14.8)


def test_wrench_bounds_are_the_extremes_each_dof_can_receive(heavy):
    # surge: the four horizontals each give 0.7071 of 51.5 N forward or of 39.9 N reverse
    assert heavy.wrench_upper[0] == pytest.approx(2 * S * 51.5 + 2 * S * 39.9)
    assert heavy.wrench_upper[2] == pytest.approx(4 * 51.5)
    assert heavy.wrench_lower[2] == pytest.approx(-4 * 39.9)


# --- rank check -------------------------------------------------------------------------------


def t200(name, position, axis):
    return Thruster.t200(name, position, axis)


def standard_bluerov2(vertical_y=0.11):
    """6 thrusters: the Heavy's four horizontals and two verticals on the centre line in x."""
    horizontals = [t200(f"h{i}", flu_to_frd(r), flu_to_frd(a))
                   for i, (r, a) in enumerate(zip(HEAVY_FLU_POSITIONS[:4], HEAVY_FLU_AXES[:4],
                                                  strict=True))]
    verticals = [t200("v1", (0.0, vertical_y, 0.0), (0, 0, 1)),
                 t200("v2", (0.0, -vertical_y, 0.0), (0, 0, 1))]
    return horizontals + verticals


def test_layout_without_pitch_authority_names_pitch():
    with pytest.raises(AllocationRankError, match=r"pitch moment \(q\)") as info:
        ThrusterLayout(standard_bluerov2())
    assert info.value.dofs == ("q",)


def test_layout_passes_when_the_missing_dof_is_passive():
    layout = ThrusterLayout(standard_bluerov2(), actuated=("u", "v", "w", "p", "r"))
    assert layout.actuated == ("u", "v", "w", "p", "r")


def test_coupled_dofs_are_both_named():
    # all four verticals ahead of the origin: heave and pitch always come together
    thrusters = standard_bluerov2()[:4] + [
        t200(f"v{k}", (0.1, y, 0.0), (0, 0, 1)) for k, y in enumerate((0.2, -0.2))]
    with pytest.raises(AllocationRankError) as info:
        ThrusterLayout(thrusters, actuated=("u", "v", "w", "q", "r"))
    assert info.value.dofs == ("w", "q")
    assert "heave force (w)" in str(info.value)


def test_horizontal_only_layout_names_heave_roll_pitch():
    with pytest.raises(AllocationRankError) as info:
        ThrusterLayout(standard_bluerov2()[:4])
    assert info.value.dofs == ("w", "p", "q")


# --- a user's own table -----------------------------------------------------------------------


def heavy_table(**changes):
    table = {
        "name": "my_heavy",
        "axes": "flu",
        "defaults": {"model": "T200", "voltage": 16},
        "thrusters": [{"name": f"t{i + 1}", "position": list(r), "axis": list(a)}
                      for i, (r, a) in enumerate(zip(HEAVY_FLU_POSITIONS, HEAVY_FLU_AXES,
                                                     strict=True))],
    }
    table.update(changes)
    return table


def test_user_table_in_flu_reproduces_the_bundled_layout(heavy):
    layout = ThrusterLayout.from_mapping(heavy_table())
    np.testing.assert_allclose(layout.matrix, heavy.matrix, atol=1e-15)
    np.testing.assert_array_equal(layout.upper, heavy.upper)
    assert layout.names == heavy.names
    assert layout.supply_voltage is None  # limits of its own, not a rating at one supply


def test_user_table_from_toml_file(tmp_path, heavy):
    lines = ["[thrusters]", 'axes = "flu"', "[thrusters.defaults]",
             "forward_limit = 51.5", "reverse_limit = 39.9", "time_constant = 0.03",
             "power_forward = [0.74, 1.58]", "power_reverse = [0.95, 1.62]"]
    for r, a in zip(HEAVY_FLU_POSITIONS, HEAVY_FLU_AXES, strict=True):
        lines += ["[[thrusters.thrusters]]", f"position = {list(r)}",
                  f"axis = {[float(x) for x in a]}"]
    path = tmp_path / "vehicle.toml"
    path.write_text("\n".join(lines) + "\n")
    layout = ThrusterLayout.from_toml(path)
    np.testing.assert_allclose(layout.matrix, heavy.matrix, atol=1e-15)
    assert layout.thrusters[0].forward_dead_band == 0.0
    assert layout.source == str(path)


@pytest.mark.parametrize(("change", "path", "words"), [
    ({"colour": "red"}, "colour", "unknown key"),
    ({"axes": "ned"}, "axes", "'frd' or 'flu'"),
    ({"thrusters": []}, "thrusters", "non-empty list"),
    ({"defaults": {"model": "T100"}}, "thrusters[0].model", "known models: T200"),
    ({"defaults": {"model": "T200", "voltage": 14}}, "thrusters[0].voltage", "14 V"),
    ({"defaults": {}}, "thrusters[0].forward_limit", "missing key (thruster 't1')"),
    ({"actuated": ["u", "x"]}, "actuated", "unknown DOF 'x'"),
])
def test_user_table_errors_name_the_key(change, path, words):
    with pytest.raises(ConfigError) as info:
        ThrusterLayout.from_mapping(heavy_table(**change), source="rov.toml")
    assert info.value.path == path
    assert str(info.value).startswith(f"rov.toml: {path}: ")
    assert words in str(info.value)


@pytest.mark.parametrize(("key", "value", "words"), [
    ("axis", [0.0, 0.0, 0.0], "thruster 't3' axis: expected a non-zero direction"),
    ("axis", [1.0, 0.0], "expected length 3"),
    ("position", [0.0, float("nan"), 0.0], "NaN"),
    ("forward_limit", -5.0, "thruster 't3' forward_limit: expected a positive number"),
    ("reverse_dead_band", 45.0, "leaves no thrust"),
    ("power_reverse", [0.95], "(coefficient, exponent)"),
    ("speed", 3.0, "unknown key"),
])
def test_user_table_errors_name_the_thruster_and_key(key, value, words):
    table = heavy_table()
    table["thrusters"][2][key] = value
    with pytest.raises(ConfigError) as info:
        ThrusterLayout.from_mapping(table)
    assert info.value.path == f"thrusters[2].{key}"
    assert words in str(info.value)


def test_duplicate_thruster_names_are_refused():
    table = heavy_table()
    table["thrusters"][4]["name"] = "t1"
    with pytest.raises(ConfigError, match=r"thrusters: duplicate thruster name 't1'"):
        ThrusterLayout.from_mapping(table)


def test_rank_deficient_user_table_names_the_file_and_dof():
    table = heavy_table()
    table["thrusters"] = table["thrusters"][:4]
    with pytest.raises(AllocationRankError, match=r"^rov\.toml: .*heave force \(w\)"):
        ThrusterLayout.from_mapping(table, source="rov.toml")


def test_missing_or_broken_thruster_file(tmp_path):
    with pytest.raises(ModelFileError, match="no such thruster file"):
        ThrusterLayout.from_toml(tmp_path / "none.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("[thrusters\n")
    with pytest.raises(ModelFileError, match="cannot read"):
        ThrusterLayout.from_toml(bad)
    other = tmp_path / "other.toml"
    other.write_text("[vehicle]\nmass = 1\n")
    with pytest.raises(ConfigError, match=r"thrusters: no such table \(top-level keys: vehicle"):
        ThrusterLayout.from_toml(other)


# --- allocation -------------------------------------------------------------------------------


def test_feasible_wrench_is_reproduced_with_least_effort(heavy, allocator):
    rng = np.random.default_rng(1)
    pinv = np.linalg.pinv(heavy.matrix)
    for _ in range(200):
        u = rng.uniform(heavy.lower, heavy.upper) * 0.3
        tau = heavy.matrix @ u
        result = allocator.allocate(tau)
        scale = max(1.0, np.abs(tau).max())
        assert np.abs(result.unmet).max() <= 2e-7 * scale  # 7e-8 at most here
        assert result.feasible
        np.testing.assert_allclose(result.produced, tau, atol=2e-7 * scale)
        # least effort: the minimum-norm forces (inside the box here)
        minimum = pinv @ tau
        if np.all((minimum > heavy.lower) & (minimum < heavy.upper)):
            np.testing.assert_allclose(result.forces, minimum, atol=1e-6 * scale)
            assert not result.saturated.any()


def kkt_violation(B, lower, upper, tau, u, weights):
    """Largest breach of the bounded least-squares optimality conditions at u (unregularised)."""
    gradient = B.T @ (weights * (B @ u - tau))
    free = (u > lower + 1e-9) & (u < upper - 1e-9)
    at_upper = u >= upper - 1e-9
    at_lower = u <= lower + 1e-9
    return max(np.abs(gradient[free]).max(initial=0.0),
               gradient[at_upper].max(initial=0.0),  # must be <= 0 at an upper bound
               (-gradient[at_lower]).max(initial=0.0))


@pytest.mark.parametrize("weights", [None, (1.0, 1.0, 1.0, 20.0, 20.0, 20.0)])
def test_infeasible_wrench_gives_the_bounded_least_squares_optimum(heavy, weights):
    allocator = ThrustAllocator(heavy, wrench_weights=weights)
    W = np.ones(6) if weights is None else np.array(weights)
    B, lower, upper = heavy.matrix, heavy.lower, heavy.upper
    rng = np.random.default_rng(2)
    infeasible = 0
    for _ in range(200):
        tau = rng.normal(size=6) * np.array([150, 150, 200, 40, 25, 40])
        result = allocator.allocate(tau)
        u = result.forces
        assert np.all(u >= lower) and np.all(u <= upper)
        np.testing.assert_allclose(result.unmet, tau - B @ u, atol=1e-12)
        infeasible += not result.feasible
        reference = lsq_linear(np.sqrt(W)[:, None] * B, np.sqrt(W) * tau,
                               bounds=(lower, upper), method="bvls", tol=1e-12)
        cost = np.sum(W * (B @ u - tau) ** 2)
        assert cost <= 2 * reference.cost * (1 + 1e-7) + 1e-8
        np.testing.assert_allclose(B @ u, B @ reference.x, atol=1e-5 * np.abs(tau).max())
        assert kkt_violation(B, lower, upper, tau, u, W) <= 1e-6 * np.abs(tau).max()
        tol = 1e-9 * upper
        np.testing.assert_array_equal(result.saturated, (u >= upper - tol) | (u <= lower + tol))
    assert infeasible > 100  # the cases did test the bounds


def test_unmet_wrench_of_a_surge_beyond_the_thrusters(heavy, allocator):
    capacity = heavy.wrench_upper[0]
    result = allocator.allocate([capacity + 50.0, 0, 0, 0, 0, 0])
    assert result.unmet[0] == pytest.approx(50.0, abs=1e-6)
    np.testing.assert_allclose(result.unmet[1:], 0.0, atol=1e-6)
    assert result.saturated[:4].all() and not result.saturated[4:].any()
    assert not result.feasible


def test_allocation_rejects_bad_wrenches(allocator):
    with pytest.raises(ShapeError, match="wrench: expected length 6"):
        allocator.allocate([1.0, 2.0])
    with pytest.raises(NonFiniteError, match="wrench contains NaN"):
        allocator.allocate([0, 0, float("nan"), 0, 0, 0])


def test_allocator_rejects_bad_settings(heavy):
    with pytest.raises(InputError, match="wrench_weights: expected positive entries"):
        ThrustAllocator(heavy, wrench_weights=[1, 1, 0, 1, 1, 1])
    with pytest.raises(InputError, match="regularization: expected a positive number"):
        ThrustAllocator(heavy, regularization=0.0)
    with pytest.raises(InputError, match="layout: expected a ThrusterLayout"):
        ThrustAllocator(heavy.matrix)


# --- dynamics: dead band, lag, power, energy --------------------------------------------------


def test_lag_is_the_exact_exponential_at_any_step(heavy):
    tau = heavy.thrusters[0].time_constant
    command = np.array([-30.0, -20.0, -10.0, 5.0, 15.0, 25.0, 35.0, 45.0])  # beyond the bands
    start = np.linspace(20.0, -10.0, 8)
    for dt in (0.001, 0.005, 0.02):
        dyn = ThrusterDynamics(heavy)
        dyn.reset(start)
        dyn.set_command(command)
        for k in range(1, 41):
            forces = dyn.step(dt)
            expected = command + (start - command) * math.exp(-k * dt / tau)
            np.testing.assert_allclose(forces, expected, rtol=1e-12, atol=1e-12)


def test_dead_band_zeroes_small_commands_by_direction(heavy):
    forward = heavy.thrusters[0].forward_dead_band  # 3.6 N
    reverse = heavy.thrusters[0].reverse_dead_band  # 2.8 N
    dyn = ThrusterDynamics(heavy)
    command = np.array([forward * 0.99, forward * 1.01, -reverse * 0.99, -reverse * 1.01,
                        -3.2, 3.2, 0.0, 10.0])
    dyn.set_command(command)
    expected = command.copy()
    expected[[0, 2, 5]] = 0.0  # 3.2 N is below the forward band, above the reverse one
    np.testing.assert_array_equal(dyn.command, expected)
    dyn.step(1.0)  # 33 time constants
    np.testing.assert_allclose(dyn.forces, expected, atol=1e-12)


def test_commands_beyond_the_limits_are_clamped_and_flagged(heavy):
    dyn = ThrusterDynamics(heavy)
    dyn.set_command([80.0, -60.0, 51.5, -39.9, 51.0, 0.0, 0.0, 0.0])
    np.testing.assert_array_equal(dyn.command[:5], [51.5, -39.9, 51.5, -39.9, 51.0])
    np.testing.assert_array_equal(dyn.saturated, [True, True, True, True] + [False] * 4)


def test_power_and_energy_follow_the_fit(heavy):
    dyn = ThrusterDynamics(heavy)
    forces = np.array([51.5, 20.0, 5.0, 0.0, -39.9, -20.0, -5.0, 10.0])
    dyn.reset(forces)
    dyn.set_command(forces)
    expected = np.array([0.74 * f ** 1.58 if f >= 0 else 0.95 * (-f) ** 1.62 for f in forces])
    np.testing.assert_allclose(dyn.power, expected, rtol=1e-12)
    np.testing.assert_allclose(heavy.power(forces), expected, rtol=1e-12)
    for _ in range(1000):
        dyn.step(0.002)
    np.testing.assert_allclose(dyn.energy_per_thruster, expected * 2.0, rtol=1e-9)
    assert dyn.energy == pytest.approx(expected.sum() * 2.0, rel=1e-9)
    # about 375 W at the 16 V forward maximum
    assert dyn.power[0] == pytest.approx(0.74 * math.exp(1.58 * math.log(51.5)))


def test_energy_of_a_lagging_force_converges_to_the_integral_of_power(heavy):
    tau = heavy.thrusters[0].time_constant
    T = 0.2
    t = np.linspace(0.0, T, 200001)
    force = 40.0 * (1.0 - np.exp(-t / tau))
    exact = np.trapezoid(0.74 * force ** 1.58, t)  # fine grid: the integral of the closed form
    errors = []
    for dt in (0.004, 0.002, 0.001):
        dyn = ThrusterDynamics(heavy)
        dyn.set_command(np.full(8, 40.0))
        for _ in range(round(T / dt)):
            dyn.step(dt)
        errors.append(abs(dyn.energy_per_thruster[0] - exact))
    assert errors[-1] < 1e-6 * exact  # 1 ms steps
    # at least second order (the trapezoid; ~2.6 here, as |T|^1.58 is not smooth at T = 0)
    assert errors[0] / errors[1] > 3.6
    assert errors[1] / errors[2] > 3.6


def test_wrench_is_the_matrix_times_the_forces(heavy):
    dyn = ThrusterDynamics(heavy)
    forces = np.linspace(-10.0, 12.0, 8)
    dyn.reset(forces)
    np.testing.assert_allclose(dyn.wrench(), heavy.matrix @ forces)


def test_dynamics_rejects_bad_input(heavy):
    dyn = ThrusterDynamics(heavy)
    with pytest.raises(ShapeError, match="command: expected length 8"):
        dyn.set_command(np.zeros(6))
    with pytest.raises(NonFiniteError, match="command contains NaN"):
        dyn.set_command([0, 0, 0, float("nan"), 0, 0, 0, 0])
    with pytest.raises(InputError, match="dt: expected a positive number"):
        dyn.step(0.0)
    with pytest.raises(InputError, match="forces: thruster 't2' at 60 N is outside"):
        dyn.reset([0, 60, 0, 0, 0, 0, 0, 0])
