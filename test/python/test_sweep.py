"""Sweeps (issue 11): designs, rows, refusals, the command line and its map, and Dask."""
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest

import spinning_top as st
from spinning_top import sweep


def test_grid_design_varies_the_first_key_slowest():
    cases = sweep.design({"initial/spin": (0, 200, 3), "initial/tilt": [0.1, 0.2]})
    np.testing.assert_array_equal(cases["initial/spin"], [0, 0, 100, 100, 200, 200])
    np.testing.assert_array_equal(cases["initial/tilt"], [0.1, 0.2] * 3)


@pytest.mark.parametrize("kind", ["random", "sobol"])
def test_random_designs_are_reproducible_and_in_bounds(kind):
    a = sweep.design({"initial/spin": (10, 20), "initial/tilt": (0, 1)}, kind, 64, seed=7)
    b = sweep.design({"initial/spin": (10, 20), "initial/tilt": (0, 1)}, kind, 64, seed=7)
    c = sweep.design({"initial/spin": (10, 20), "initial/tilt": (0, 1)}, kind, 64, seed=8)
    np.testing.assert_array_equal(a["initial/spin"], b["initial/spin"])
    assert not np.array_equal(a["initial/spin"], c["initial/spin"])
    assert a["initial/spin"].min() >= 10 and a["initial/spin"].max() < 20


def test_outcome_columns_are_run_cases_columns_in_order():
    # One list (the core's): what run_cases returns, a refused case's row included, and what the
    # sweep's rows and descriptions name.
    columns = st.run_cases({"scene": "fixed_tip"}, {"initial/spin": np.array([150.0, 2e9])}, st.CaseSettings(0.1))
    assert list(columns) == list(sweep.OUTCOME_COLUMNS)
    assert list(columns["outcome"]) == ["none", "refused"]
    assert all(len(columns[name]) == 2 for name in columns)
    assert all(description for description in sweep.OUTCOME_COLUMNS.values())


def test_rows_equal_single_runs_whatever_the_batching():
    base = {"scene": "fixed_tip", "initial/precession_rate": 0.0}
    cases = sweep.design({"initial/spin": (0, 200, 9), "initial/tilt": (0, 1.4, 5)})
    one = sweep.run(base, cases, workers=1, batch_size=45)
    many = sweep.run(base, cases, workers=2, batch_size=4)
    pd.testing.assert_frame_equal(one, many, check_exact=True)
    for i in (0, 13, 44):
        row = st.run_case({**base, "initial/spin": cases["initial/spin"][i], "initial/tilt": cases["initial/tilt"][i]})
        for name in ("outcome", "end_time", "min_normal_force", "max_tilt", "final_energy", "method"):
            assert one[name][i] == row[name] or (pd.isna(one[name][i]) and pd.isna(row[name]))


def test_a_bad_key_is_refused_before_running_and_a_bad_case_is_a_row():
    with pytest.raises(st.InvalidParameter) as refused:
        sweep.run({"scene": "fixed_tip"}, {"initial/spinn": np.array([1.0, 2.0])})
    assert refused.value.key == "initial/spinn"
    assert "did you mean initial/spin?" in str(refused.value)
    # C > 2A for the second case only: that row is refused, with the core's message.
    rows = sweep.run({"scene": "fixed_tip"}, {"inertia_axial": np.array([6e-5, 9e-5])})
    assert list(rows["outcome"]) == ["none", "refused"]
    assert rows["message"][1].startswith("inertia_axial: C = 9e-05 exceeds 2A")
    assert np.isnan(rows["end_time"][1])


def test_viscous_rows_sample_the_time_stepper(tmp_path):
    rows = sweep.run({"scene": "viscous", "friction": 1e-3}, {"initial/spin": np.array([0.0, 150.0])}, duration=1.0)
    assert list(rows["outcome"]) == ["fallen", "none"]
    assert (rows["method"] == "dop853").all()
    assert rows["friction_work"][1] > 0.0
    assert rows["energy_balance_error"].max() < 1e-9
    # A map of another column than the event time (a random design: drawn as points).
    from spinning_top import stability_map
    cases = sweep.design({"friction": (1e-4, 1e-2), "initial/spin": (100, 200)}, "random", 6, seed=2)
    rows = sweep.run({"scene": "viscous"}, cases, duration=0.2)
    stability_map.plot(rows, "friction", "initial/spin", tmp_path / "tilt.png", value="final_tilt")
    assert (tmp_path / "tilt.png").read_bytes()[:4] == b"\x89PNG"


def test_command_line_writes_rows_and_a_map(tmp_path, source_dir):
    output, picture = tmp_path / "map.csv", tmp_path / "map.png"
    # Tilts up to 1.4 rad: the needle (no rim), since the scene file's rim touches the floor at 0.857 rad.
    result = subprocess.run(
        [sys.executable, "-m", "spinning_top.sweep", "--config", str(source_dir / "config" / "fixed_tip.yaml"),
         "--set", "rim_radius=0", "--set", "rim_distance=0",
         "--vary", "initial/spin=0:200:21", "--vary", "initial/tilt=0:1.4:8", "--output", str(output),
         "--plot", str(picture), "--no-progress"], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    rows = pd.read_csv(output)
    assert len(rows) == 168
    assert set(rows["outcome"]) == {"none", "fallen"}
    assert list(rows.columns[:2]) == ["initial/spin", "initial/tilt"]
    assert picture.stat().st_size > 20000 and picture.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "sweep: 168 cases:" in result.stderr


@pytest.mark.parametrize("arguments, message", [
    (["--vary", "initial/spinn=0:1:2"], "initial/spinn: unknown key"),
    (["--vary", "initial/spin=0:1:x"], "--vary initial/spin: expected LOW:HIGH[:N]"),
    (["--vary", "initial/spin=0:200"], "initial/spin: a grid axis is (low, high, n)"),
    (["--vary", "initial/spin=0:200:5", "--design", "sobol", "--cases", "8"], "a sobol axis is (low, high)"),
    (["--vary", "initial/spin=0:1:2", "--duration", "-1"], "duration: must be a finite number > 0"),
    (["--vary", "initial/spin=0:1:2", "--output", "rows.parquet"], "Parquet needs pyarrow"),
    (["--vary", "initial/spin=0:1:2", "--vary", "initial/tilt=0:1:2", "--plot", "m.png", "--value", "method"],
     "--value method: not a numeric column"),
    (["--vary", "initial/spin=0:1:2", "--vary", "initial/tilt=0:1:2", "--plot", "m.png", "--x", "mass"],
     "--x mass: not a varied key"),
])
def test_command_line_refuses_bad_input(tmp_path, source_dir, arguments, message):
    result = subprocess.run([sys.executable, "-m", "spinning_top.sweep", "--config",
                             str(source_dir / "config" / "fixed_tip.yaml"), "--no-progress", *arguments],
                            capture_output=True, text=True, cwd=tmp_path)
    assert result.returncode != 0
    assert message in result.stderr


def test_dask_local_cluster_gives_the_local_rows_bit_for_bit():
    import faulthandler

    from distributed import Client, LocalCluster

    # A cluster that cannot start (a worker failing to import the module) would otherwise wait
    # for its workers until CI's limit: fail after 120 s with every thread's stack instead.
    faulthandler.dump_traceback_later(120, exit=True)

    base = {"scene": "frictionless", "initial/precession_rate": 0.0}
    cases = sweep.design({"initial/spin": (0, 200), "initial/tilt": (0, 1.4)}, "sobol", 256, seed=1)
    local = sweep.run(base, cases)
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, \
            Client(cluster) as client:
        remote = sweep.run(base, cases, scheduler=client, batch_size=16)
        assert len(client.nthreads()) == 2
    faulthandler.cancel_dump_traceback_later()
    pd.testing.assert_frame_equal(local, remote, check_exact=True)
    assert local.to_csv(index=False) == remote.to_csv(index=False)


def test_hops_are_rows_and_a_map(tmp_path):
    # The toy top on its pivot launched with a precession (the README's lift-off map). Upright, or
    # without precession, it stays on the floor. Tilted 1 rad: at -40 rad/s R < 0 at the release,
    # and it flies from t = 0 and hops; at +40 rad/s R reaches 0 at 15.5 ms where the free tip
    # would not rise, and a pivot that may neither push nor let go ends the run (HYBRID.md).
    from spinning_top import stability_map
    base = {"scene": "fixed_tip", "initial/spin": 150.0}
    cases = sweep.design({"initial/precession_rate": [-40.0, 0.0, 40.0], "initial/tilt": [0.1, 1.0]})
    rows = sweep.run(base, cases, duration=1.0)
    hopped = rows["lift_offs"] > 0
    assert list(hopped) == [False, True, False, False, False, False]
    assert list(rows["outcome"]) == ["none"] * 5 + ["lift_off"]
    assert rows["first_lift_off_time"][1] == 0.0 and rows["landings"][1] >= 1 and rows["max_hop_height"][1] > 1e-3
    assert (rows["max_hop_height"][~hopped] == 0).all() and (rows["landings"][~hopped] == 0).all()
    assert rows["first_lift_off_time"][5] == rows["event_time"][5] == pytest.approx(0.0155, abs=1e-4)
    assert rows["first_lift_off_time"][[0, 2, 3, 4]].isna().all()
    # after_lift_off stop: the same lift-offs end the runs, none counted as a hop.
    stopped = sweep.run({**base, "after_lift_off": "stop"}, cases, duration=1.0)
    assert list(stopped["outcome"]) == ["none", "lift_off", "none", "none", "none", "lift_off"]
    assert (stopped["lift_offs"] == 0).all()
    np.testing.assert_array_equal(stopped["event_time"][[1, 5]], rows["first_lift_off_time"][[1, 5]])
    assert list(stability_map.shown_outcomes(rows)) == ["none", "hops", "none", "none", "none", "lift_off"]
    assert list(stability_map.shown_outcomes(stopped))[1] == "at_release"
    stability_map.plot(rows, "initial/precession_rate", "initial/tilt", tmp_path / "hops.png", value="max_hop_height")
    assert (tmp_path / "hops.png").read_bytes()[:4] == b"\x89PNG"
