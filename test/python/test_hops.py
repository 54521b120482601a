"""The top goes on (issue 18, doc/spec/HYBRID.md) as the Python module shows it: Simulator.run's
phase, tip height and transition rows, and run_case's hop columns, checked against the physics of
each phase. test_hybrid_reference.py checks the same run against an independent integration."""
import math

import numpy as np
import pytest

import spinning_top as st

TOY = {"mass": 0.1, "inertia_transverse": 4e-5, "inertia_axial": 6e-5, "tip_distance": 0.02, "gravity": 9.80665}
#: The issue's frictionless top that hops: lifts off at 9.4 ms, 7 flights within 0.3 s.
HOPPER = {**TOY, "scene": "frictionless", "initial/tilt": 0.8, "initial/precession_rate": 60.0, "initial/spin": 150.0}
DURATION = 0.3


def rotate(q, v):
    """Rows of body vectors v turned into the world by the rows of quaternions q = (w, x, y, z)."""
    w, u = q[:, :1], q[:, 1:]
    t = 2.0 * np.cross(u, v)
    return v + w * t + np.cross(u, t)


def angular_momentum(run):
    """L about G in the world: Q diag(A, A, C) omega_b."""
    inertia = np.array([TOY["inertia_transverse"], TOY["inertia_transverse"], TOY["inertia_axial"]])
    return rotate(run["attitude"], run["body_rates"] * inertia)


def tip_velocity(run):
    """v_P = v_G + omega x (P - G), P - G = -h e_Z."""
    omega = rotate(run["attitude"], run["body_rates"])
    axis = rotate(run["attitude"], np.tile([0.0, 0.0, 1.0], (len(run["time"]), 1)))
    return run["center_of_mass_velocity"] + np.cross(omega, -TOY["tip_distance"] * axis)


def flights(run):
    """(first, last) row indices of each flight: from a lift_off row to the row before the landing."""
    events = run["events"]
    starts = np.flatnonzero(events == "lift_off")
    landings = np.flatnonzero(events == "landing")
    spans = []
    for start in starts:
        after = landings[landings > start]
        spans.append((start, after[0] - 1 if len(after) else len(events) - 1))
    return spans


@pytest.fixture(scope="module")
def hopper_run():
    # 10 kHz: ~30 rows per flight of the shortest hops, and the transition rows between them.
    return st.Simulator(HOPPER).run(np.arange(3001) / 1e4)


def test_the_phases_rows(hopper_run):
    run = hopper_run
    phase, events, height, force = run["phase"], run["events"], run["tip_height"], run["normal_force"]
    assert set(phase) == {"contact", "flight"} and run["event"] == ""
    # The first lift-off is the issue's, at R = 0.
    first = np.flatnonzero(events == "lift_off")[0]
    assert run["time"][first] == pytest.approx(0.0094, abs=1e-4)
    assert (force[:first] > 0.0).all() and force[first] == 0.0
    # Frictionless: always flight after a lift-off, at the floor (z_P = 0), with no floor force.
    lift_offs = events == "lift_off"
    assert (phase[lift_offs] == "flight").all() and (height[lift_offs] == 0.0).all()
    in_air = (phase == "flight") & ~lift_offs
    assert in_air.sum() > 1000
    assert (force[phase == "flight"] == 0.0).all() and (run["contact_force"][phase == "flight"] == 0.0).all()
    assert (height[in_air] > 0.0).all()
    # The tip on the floor in contact, landings included; the floor pushes (R >= 0).
    landings = events == "landing"
    assert landings.sum() >= 5 and (phase[landings] == "contact").all()
    assert (height[phase == "contact"] == 0.0).all() and (force[phase == "contact"] >= 0.0).all()
    # The tip height is contact_point's z (simulate's pz).
    np.testing.assert_array_equal(height, run["contact_point"][:, 2])


def test_flight_is_a_parabola_and_a_free_rotation(hopper_run):
    run = hopper_run
    g = TOY["gravity"]
    for first, last in flights(run):
        t = run["time"][first:last + 1] - run["time"][first]
        centre = run["center_of_mass"][first:last + 1]
        v0 = run["center_of_mass_velocity"][first]
        # G(t) = G0 + v0 t - g t^2 / 2 e_z; frictionless: no horizontal motion at all. Round-off of
        # ~2e-2 m positions: 1e-15 m is a few ulps.
        assert np.abs(centre[:, :2] - centre[0, :2]).max() <= 1e-15
        parabola = centre[0, 2] + v0[2] * t - 0.5 * g * t * t
        assert np.abs(centre[:, 2] - parabola).max() < 1e-15
        # L about G is constant (torque-free); |L| ~ 1e-2 kg m^2/s, 1e-14 relative is round-off.
        momentum = angular_momentum(run)[first:last + 1]
        assert np.abs(momentum - momentum[0]).max() < 1e-14 * np.linalg.norm(momentum[0])


def test_energy_goes_only_into_the_landings(hopper_run):
    run = hopper_run
    energy, lost = run["energy"], run["friction_work"]  # frictionless: the landings' losses alone
    # E + (the landings' losses) is E0 throughout; exact contact phases and the closed-form flight
    # keep it to round-off of E0 ~ 0.7 J (an ulp is 1.1e-16 J; measured 3.3e-16 J).
    assert np.abs(energy + lost - energy[0]).max() < 1e-14
    # Each plastic landing loses kinetic energy (HYBRID.md: it never grows), and only landings do.
    landings = np.flatnonzero(run["events"] == "landing")
    steps = np.diff(lost)
    assert (steps[landings - 1] > 0.0).all()
    others = np.setdiff1d(np.arange(len(steps)), landings - 1)
    assert np.abs(steps[others]).max() < 1e-15


def test_a_plastic_landing_stops_the_tips_fall(hopper_run):
    run = hopper_run
    landings = run["events"] == "landing"
    # v_Pz+ = 0 after the impulse: at the landing rows (the state after it). Tip speeds are ~1 m/s.
    assert np.abs(tip_velocity(run)[landings, 2]).max() < 1e-14
    # Frictionless: the impulse is vertical, so G has no horizontal velocity, ever.
    assert np.abs(run["center_of_mass_velocity"][:, :2]).max() == 0.0


def test_run_case_counts_the_runs_transitions(hopper_run):
    run = hopper_run
    row = st.run_case(HOPPER, duration=DURATION)
    assert row["outcome"] == "none" and math.isnan(row["event_time"])
    assert row["lift_offs"] == (run["events"] == "lift_off").sum() == 7
    assert row["landings"] == (run["events"] == "landing").sum() == 7
    # The same located time, whichever times were asked for (exact: the contact phase's closed form).
    assert row["first_lift_off_time"] == pytest.approx(run["time"][run["events"] == "lift_off"][0], abs=1e-15)
    assert row["min_normal_force"] == 0.0  # the flights' R
    assert row["friction_work"] == pytest.approx(run["friction_work"][-1], abs=1e-15)


def test_max_hop_height_bounds_a_dense_run():
    # Rows every dt miss the peak by at most max|z_P''| (dt/2)^2 / 2. In flight z_P = z_G - h e_Zz
    # with z_G'' = -g, and e_Z precesses about L at Omega = |L| / A, so |e_Zz''| <= Omega^2:
    # |z_P''| <= g + h Omega^2 (about 1.2e3 m/s^2 here: 1.5e-8 m at dt = 1e-5 s).
    dt = 1e-5
    run = st.Simulator(HOPPER).run(np.arange(int(round(DURATION / dt)) + 1) * dt)
    row = st.run_case(HOPPER, duration=DURATION)
    omega = np.linalg.norm(angular_momentum(run), axis=1).max() / TOY["inertia_transverse"]
    bound = 0.5 * (TOY["gravity"] + TOY["tip_distance"] * omega ** 2) * (dt / 2) ** 2
    sampled = run["tip_height"].max()
    assert 0.0 <= row["max_hop_height"] - sampled <= bound + 1e-17
    assert row["max_hop_height"] == pytest.approx(0.010349, abs=1e-6)  # ~half of h: a visible hop


def test_stop_ends_the_run_at_the_lift_off(hopper_run):
    keys = {**HOPPER, "after_lift_off": "stop"}
    row = st.run_case(keys, duration=DURATION)
    assert row["outcome"] == "lift_off"
    assert row["lift_offs"] == 0 and row["landings"] == 0 and row["max_hop_height"] == 0.0
    # The same lift-off as the flying run's first, now the terminal event.
    flying = hopper_run["time"][hopper_run["events"] == "lift_off"][0]
    assert row["first_lift_off_time"] == row["event_time"] == pytest.approx(flying, abs=1e-15)
    run = st.Simulator(keys).run(np.arange(301) / 1e3)
    assert run["event"] == "lift_off" and run["events"][-1] == "lift_off"
    assert (run["phase"] == "contact").all() and (run["events"][:-1] == "").all()
    assert run["time"][-1] == row["event_time"]


def test_a_pivot_sticks_where_it_lands(source_dir):
    # The fixed tip of the extreme lift-off case flies at 21.1 ms; landing, the tip's velocity is
    # cancelled in full (HYBRID.md: v_P+ = 0 with e = 0), and it pivots there until it lifts off again.
    keys = st.load_scene(source_dir / "config" / "extreme" / "lift_off.yaml")
    run = st.Simulator(keys).run(np.arange(1001) / 1e4)
    events, phase = run["events"], run["phase"]
    landings = np.flatnonzero(events == "landing")
    assert len(landings) >= 1
    # Tip speeds here are ~1 m/s: 1e-14 m/s is round-off.
    assert np.abs(tip_velocity(run)[landings]).max() < 1e-14
    for landing in landings:
        after = np.flatnonzero(events[landing + 1:] == "lift_off")
        end = landing + 1 + after[0] if len(after) else len(events)
        pivot = run["contact_point"][landing:end]
        assert (phase[landing:end] == "contact").all()
        assert np.abs(pivot - pivot[0]).max() <= 1e-17  # the pivot does not move
    row = st.run_case(keys, duration=0.1)
    assert row["lift_offs"] == (events == "lift_off").sum() and row["landings"] == len(landings)


def test_transitions_passed_by_advance_to_are_taken_not_rows():
    sim = st.Simulator(HOPPER)
    sim.advance_to(0.1)
    taken = sim.take_transitions()
    assert [event for event, _ in taken] == ["lift_off", "landing", "lift_off"]
    assert taken[1][1]["phase"] == "contact" and taken[1][1]["tip_height"] == 0.0
    assert sim.take_transitions() == []
    assert sim.phase == "flight" and sim.hops()["lift_offs"] == 2
    # Transitions left untaken (the landing at 0.140 s) are not run()'s rows: its rows start at the
    # time asked for.
    sim.advance_to(0.145)
    run = sim.run([0.15, 0.2])
    assert run["time"][0] >= 0.15


@pytest.mark.parametrize("scene", ["fixed_tip", "frictionless", "viscous"])
def test_a_lift_off_at_the_release_shows_no_pulling_floor(scene):
    """Issue 19, item 9: released where R < 0 with after_lift_off: stop, the run ends with lift_off
    at t = 0, and the floor force it shows is 0, not the negative R of the invalid contact state."""
    case = {**TOY, "scene": scene, "initial/tilt": 0.5, "initial/nutation_rate": 60.0, "initial/spin": 150.0,
            "after_lift_off": "stop"}
    if scene == "viscous":
        case["friction"] = 0.02
    row = st.run_case(case, duration=0.1)
    assert row["outcome"] == "lift_off"
    assert row["event_time"] == 0.0
    assert row["min_normal_force"] == 0.0
    traj = st.Simulator(case).run(np.array([0.0, 0.01]))
    assert traj["event"] == "lift_off"
    assert np.all(traj["normal_force"] >= 0.0)
