"""The Python module (issue 11) is the core: the same numbers as `simulate`, bit for bit, the
same refusals with the same messages, and physics checked against closed forms."""
import io
import math
import subprocess

import numpy as np
import pytest
from scipy import integrate

import spinning_top as st

SCENES = ["fixed_tip", "frictionless", "viscous"]


def simulate_csv(simulate, config, duration, rate, sets=()):
    command = [simulate, "--config", str(config), "--duration", str(duration), "--output-rate", str(rate)]
    for s in sets:
        command += ["--set", s]
    out = subprocess.run(command, check=True, capture_output=True, text=True).stdout
    lines = out.splitlines()
    assert lines[0].startswith("# integrator: ")
    header = lines[1].split(",")
    assert header[-2:] == ["phase", "event"]
    rows = [line.split(",") for line in lines[2:]]
    columns = {name: np.array([float(r[i]) for r in rows]) for i, name in enumerate(header[:-2])}
    columns["phase"] = [r[-2] for r in rows]
    columns["events"] = [r[-1] for r in rows]  # a transition's name on its row, the terminal event on the last
    columns["event"] = rows[-1][-1]
    return lines[0][len("# integrator: "):], columns


#: A frictionless top that lifts off at 9.4 ms and hops (HYBRID.md): transition rows between the
#: requested ones.
HOPS = ("initial/tilt=0.8", "initial/precession_rate=60")


@pytest.mark.parametrize("scene, sets", [(scene, sets) for sets in [(), ("initial/spin=0",)] for scene in SCENES] +
                         [("frictionless", HOPS), ("viscous", HOPS)],
                         ids=[f"{scene}-{what}" for what in ("spinning", "spinless_falls") for scene in SCENES] +
                         ["frictionless-hops", "viscous-hops"])
def test_run_equals_simulate_bit_for_bit(simulate, source_dir, scene, sets):
    config = source_dir / "config" / f"{scene}.yaml"
    description, csv = simulate_csv(simulate, config, 2.0, 100, sets)
    overrides = dict(s.split("=", 1) for s in sets)
    sim = st.simulator_from_file(config, overrides)
    assert sim.integrator_description() == description
    # simulate's instants: i / rate, one division each (SampleTimes).
    trajectory = sim.run(np.arange(201) / 100.0)
    n = len(csv["t"])
    assert len(trajectory["time"]) == n
    # %.17g in the CSV reads back to the same double: equality is bit for bit.
    np.testing.assert_array_equal(trajectory["time"], csv["t"])
    np.testing.assert_array_equal(trajectory["attitude"], np.column_stack([csv[k] for k in ("qw", "qx", "qy", "qz")]))
    np.testing.assert_array_equal(trajectory["center_of_mass"], np.column_stack([csv[k] for k in ("gx", "gy", "gz")]))
    np.testing.assert_array_equal(trajectory["contact_point"], np.column_stack([csv["px"], csv["py"], csv["pz"]]))
    np.testing.assert_array_equal(trajectory["tip_height"], csv["pz"])
    np.testing.assert_array_equal(trajectory["normal_force"], csv["normal_force"])
    np.testing.assert_array_equal(trajectory["contact_force"][:, :2],
                                  np.column_stack([csv["contact_force_x"], csv["contact_force_y"]]))
    np.testing.assert_array_equal(trajectory["energy"], csv["energy"])
    assert trajectory["event"] == csv["event"]
    assert trajectory["phase"].tolist() == csv["phase"]
    assert trajectory["events"].tolist() == csv["events"]
    if sets == ("initial/spin=0",):
        assert trajectory["event"] == "fallen"
    if sets == HOPS:
        assert {"lift_off", "landing"} <= set(csv["events"]) and n > 201  # rows at the transitions too


def test_values_reach_the_core_unchanged():
    # A float goes through text with 17 digits: the double the core gets is the caller's.
    spin = 150.00000000000003
    a = st.Simulator({"scene": "fixed_tip", "initial/tilt": 0.3, "initial/spin": spin})
    b = st.Simulator({"scene": "fixed_tip", "initial/tilt": "0.3", "initial/spin": repr(spin)})
    a.advance_to(1.0)
    b.advance_to(1.0)
    np.testing.assert_array_equal(a.snapshot()["attitude"], b.snapshot()["attitude"])
    assert a.snapshot()["body_rates"][2] == spin


@pytest.mark.parametrize("key, value", [("inertia_axal", "1"), ("inertia_axial", "1"), ("initial/tilt", "2.0"),
                                        ("integrator", "rk5"), ("mass", "heavy")])
def test_bad_key_or_value_is_refused_with_the_cores_message(simulate, source_dir, key, value):
    config = source_dir / "config" / "fixed_tip.yaml"
    result = subprocess.run([simulate, "--config", str(config), "--set", f"{key}={value}"], capture_output=True, text=True)
    assert result.returncode == 2
    with pytest.raises(st.InvalidParameter) as refused:
        st.simulator_from_file(config, {key: value})
    assert isinstance(refused.value, ValueError)
    message = str(refused.value)
    assert message.startswith(key + ": ") or message.startswith(refused.value.key + ": ")
    # simulate prints the core's message, then where the value came from.
    assert f"simulate: error: {message} (from --set {key}={value})" in result.stderr
    with pytest.raises(st.InvalidParameter):
        st.run_case(st.load_scene(config, {key: value}))


def test_scene_file_errors_are_reported(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("scene: fixed_tip\ninitial: [1, 2]\n")
    with pytest.raises(st.SceneFileError, match="initial: a list is not a valid value"):
        st.read_scene_file(str(bad))


def test_run_has_the_snapshots_fields_at_each_time():
    # Simulator.run's columns and Simulator.snapshot()'s keys are one list of a state's fields (the
    # snapshot adds L_z): the run's last row is the snapshot after it, bit for bit.
    keys = {"scene": "viscous", "friction": 0.05, "initial/velocity_x": 0.1}
    trajectory = st.Simulator(keys).run(np.linspace(0.0, 0.5, 11))
    sim = st.Simulator(keys)
    sim.advance_to(0.5)
    snapshot = sim.snapshot()
    assert [key for key in trajectory if key not in ("events", "event")] == \
        [key for key in snapshot if key != "vertical_angular_momentum"]
    for key, column in trajectory.items():
        if key not in ("events", "event"):
            np.testing.assert_array_equal(column[-1], snapshot[key])


def test_step_budget_stops_a_run():
    sim = st.Simulator({"scene": "fixed_tip", "initial/tilt": 0.3, "initial/spin": 150, "integrator": "rk4",
                        "step": 1e-5})
    with pytest.raises(st.StepBudgetExceeded, match="max_steps"):
        sim.run(np.linspace(0, 1, 11), max_steps=1000)
    assert sim.steps <= 1000


def test_run_refuses_times_it_cannot_show():
    sim = st.Simulator({"scene": "fixed_tip", "initial/tilt": 0.3, "initial/spin": 150})
    with pytest.raises(ValueError, match="increasing"):
        sim.run([0.0, 0.2, 0.1])
    sim.advance_to(1.0)
    with pytest.raises(ValueError, match="at or after"):
        sim.run([0.5, 1.5])
    assert sim.run([1.0, 1.5])["time"].tolist() == [1.0, 1.5]


@pytest.mark.parametrize("integrator", ["auto", "dop853"])
def test_non_finite_times_and_bad_step_allowances_are_refused(integrator):
    sim = st.Simulator({"scene": "fixed_tip", "initial/tilt": 0.3, "initial/spin": 150, "integrator": integrator})
    for t in (math.inf, math.nan):
        with pytest.raises(ValueError, match="target time must be finite"):
            sim.advance_to(t)
    with pytest.raises(ValueError, match="must be increasing|start at or after"):
        sim.run([0.0, math.nan])
    with pytest.raises(ValueError, match="target time must be finite"):
        sim.run([0.0, math.inf])
    for steps in (0, -1, 2.5, math.nan):
        with pytest.raises(ValueError, match="max_steps: must be a whole number >= 1"):
            sim.advance_to(1.0, max_steps=steps)
    assert sim.time == 0.0 and sim.event == ""  # nothing moved
    assert sim.advance_to(1.0) == "" and sim.time == 1.0


def test_integrator_description_and_choice():
    sim = st.Simulator({"scene": "viscous", "friction": 1e-3})
    assert sim.integrator_description().startswith("auto: dop853")
    assert sim.integrator_choice()["method"] == "dop853"
    assert st.Simulator({"scene": "fixed_tip"}).integrator_choice()["method"] == "exact"


def test_parameter_specs_are_the_cores_keys():
    keys = [s["key"] for s in st.parameter_specs()]
    assert {"scene", "mass", "initial/spin", "friction", "integrator"} <= set(keys)


# --- physics of run_case ---------------------------------------------------------------------

TOY = {"mass": 0.1, "inertia_transverse": 4e-5, "inertia_axial": 6e-5, "tip_distance": 0.02, "gravity": 9.80665}


def fall_time(scene, tilt):
    """Time for a spinless top released at rest at `tilt` to reach the floor (theta = pi/2), from
    energy conservation: thetadot^2 = 2 m g h (cos theta0 - cos theta) / A'(theta), A' = A0 on the
    pivot, A + m h^2 sin^2 theta on the frictionless floor (G moves vertically only). theta =
    theta0 + x^2 removes the 1/sqrt singularity at the release."""
    m, a, h, g = TOY["mass"], TOY["inertia_transverse"], TOY["tip_distance"], TOY["gravity"]

    def inertia(theta):
        return a + m * h * h if scene == "fixed_tip" else a + m * h * h * math.sin(theta) ** 2

    def integrand(x):
        theta = tilt + x * x
        if x == 0.0:
            return 2.0 / math.sqrt(2 * m * g * h * math.sin(tilt) / inertia(tilt))
        return 2.0 * x / math.sqrt(2 * m * g * h * (math.cos(tilt) - math.cos(theta)) / inertia(theta))

    value, error = integrate.quad(integrand, 0.0, math.sqrt(math.pi / 2 - tilt), epsabs=0, epsrel=1e-13, limit=200)
    return value


@pytest.mark.parametrize("scene", ["fixed_tip", "frictionless"])
@pytest.mark.parametrize("tilt", [0.1, 0.5, 1.2])
def test_spinless_top_falls_at_the_quadrature_time(scene, tilt):
    row = st.run_case({**TOY, "scene": scene, "initial/tilt": tilt, "initial/spin": 0.0})
    assert row["outcome"] == "fallen"
    assert row["event_time"] == pytest.approx(fall_time(scene, tilt), rel=1e-10)
    assert row["max_tilt"] == pytest.approx(math.pi / 2, abs=1e-12)


@pytest.mark.parametrize("scene", ["fixed_tip", "frictionless"])
def test_tops_above_the_sleeping_threshold_released_upright_stay_up(scene):
    m, a, c, h, g = (TOY[k] for k in ("mass", "inertia_transverse", "inertia_axial", "tip_distance", "gravity"))
    transverse = a + m * h * h if scene == "fixed_tip" else a
    critical = 2 * math.sqrt(transverse * m * g * h) / c
    from spinning_top import stability_map
    assert stability_map.sleeping_threshold({**TOY, "scene": scene}) == pytest.approx(critical, rel=1e-15)
    from spinning_top import sweep
    cases = sweep.design({"initial/spin": [1.05 * critical, 1.5 * critical, 4 * critical], "initial/tilt": [1e-4, 1e-2]})
    rows = sweep.run({**TOY, "scene": scene}, cases)
    assert (rows["outcome"] == "none").all()
    # Stable: the nutation stays near the release tilt (bounded by a few times it, not pi/2).
    assert (rows["max_tilt"] < 20 * rows["initial/tilt"]).all()
    # Below the threshold the same small tilt grows far (the upright top is unstable).
    below = st.run_case({**TOY, "scene": scene, "initial/spin": 0.9 * critical, "initial/tilt": 1e-2})
    assert below["max_tilt"] > 0.5


def test_lift_off_where_the_normal_force_reaches_zero(source_dir):
    # The contact model alone: the run ends at the lift-off (test_hops.py has the flight after it).
    keys = {**st.load_scene(source_dir / "config" / "extreme" / "lift_off.yaml"), "after_lift_off": "stop"}
    row = st.run_case(keys)
    assert row["outcome"] == "lift_off"
    mg = 0.1 * 9.80665
    assert abs(row["min_normal_force"]) <= 1e-9 * mg  # R = 0 at the event, never below
    # A time-stepper sampled every 10 us finds R = 0 at the same time.
    stepped = st.run_case({**keys, "integrator": "dop853", "tolerance": 1e-13}, sample_rate=1e5)
    assert stepped["outcome"] == "lift_off"
    assert stepped["event_time"] == pytest.approx(row["event_time"], abs=1e-9)
    assert stepped["min_normal_force"] == pytest.approx(0.0, abs=1e-8 * mg)


def test_exact_rows_keep_the_energy_balance_to_round_off():
    from spinning_top import sweep
    rows = sweep.run({"scene": "frictionless"}, sweep.design({"initial/spin": (10, 200), "initial/tilt": (0.05, 1.3)},
                                                          "sobol", 64, seed=3))
    assert (rows["method"] == "exact").all()
    assert rows["energy_balance_error"].max() < 1e-13


@pytest.mark.parametrize("scene", ["fixed_tip", "frictionless"])
@pytest.mark.parametrize("fraction", [0.5, 0.69, 0.72, 0.8, 0.95])
def test_released_near_upright_below_the_threshold_the_top_nutates_to_the_cubics_root(scene, fraction):
    # Released at rest (apart from spin) at u0 = cos(tilt) -> 1, the cubic f(u) = (1 - u) [2 m g h
    # (1 - u^2)/A' - C^2 wZ^2 (1 - u)/A'^2] has its lower root at 1 + u1 = 2 (wZ / w_crit)^2:
    # below w_crit the upright top is unstable, but it reaches the floor (u1 <= 0) only below
    # w_crit / sqrt(2); above, it swings down to acos(2 (wZ / w_crit)^2 - 1) and back.
    from spinning_top import stability_map
    critical = stability_map.sleeping_threshold({**TOY, "scene": scene})
    row = st.run_case({**TOY, "scene": scene, "initial/spin": fraction * critical, "initial/tilt": 1e-6})
    lowest = 2 * fraction ** 2 - 1
    if lowest <= 0:
        assert row["outcome"] == "fallen"
    else:
        assert row["outcome"] == "none"
        # The release 1e-6 rad off the vertical moves the root by O(1e-12).
        assert row["max_tilt"] == pytest.approx(math.acos(lowest), abs=1e-9)
