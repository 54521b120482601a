"""The sweep's command line against bad input (issue 19): every refusal is one line naming the
option (`sweep: error: --option: ...`, exit status 2) and comes before any case runs; rows that
cannot be written where asked are kept in a file the error names."""
import os
import resource
import socket
import subprocess
import sys
import tempfile

import numpy as np
import pandas as pd
import pytest

from spinning_top import sweep

GRID = "initial/spin=0:1:3"
TWO = ["--vary", GRID, "--vary", "initial/tilt=0:1:2"]


@pytest.fixture
def sweep_main(capsys, monkeypatch, source_dir, tmp_path):
    """Runs sweep.main in this process (fast); returns (status, stderr lines, cases run)."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path / "tmp"))
    for directory in ("tmp", "dir.csv", "dir.png"):
        (tmp_path / directory).mkdir()
    ran = []
    real_run = sweep.run

    def counting_run(base, cases, *args, **kwargs):
        ran.append(len(next(iter(cases.values()))))
        return real_run(base, cases, *args, **kwargs)

    monkeypatch.setattr(sweep, "run", counting_run)

    def main(*arguments, config=None):
        config = str(config or source_dir / "config" / "fixed_tip.yaml")
        try:
            status = sweep.main(["--config", config, "--no-progress", "--duration", "0.05", *arguments])
        except SystemExit as exit:  # argparse's refusals
            status = exit.code
        err = capsys.readouterr().err
        return status, err.splitlines(), sum(ran)
    return main


@pytest.mark.parametrize("arguments, message", [
    # Outputs that cannot be written as asked: found before the sweep runs, not after.
    (["--vary", GRID, "--output", "missing/rows.csv"], "--output: 'missing/rows.csv': no directory"),
    (["--vary", GRID, "--output", "dir.csv"], "--output: 'dir.csv' is a directory"),
    (["--vary", GRID, "--output", "."], "--output: '.' has no extension"),
    (["--vary", GRID, "--output", "/"], "--output: '/' has no extension"),
    (["--vary", GRID, "--output", "/dev/full"], "--output: '/dev/full' has no extension; give one of .csv, .parquet"),
    (["--vary", GRID, "--output", "rows.txt"], "--output: 'rows.txt' has extension .txt; give one of .csv"),
    (["--vary", GRID, "--output", "rows.parquet"], "--output: 'rows.parquet': Parquet needs pyarrow"),
    ([*TWO, "--plot", "missing/map.png"], "--plot: 'missing/map.png': no directory"),
    ([*TWO, "--plot", "map.xyz"], "--plot: 'map.xyz' has extension .xyz; give one of"),
    ([*TWO, "--plot", "map"], "--plot: 'map' has no extension"),
    ([*TWO, "--plot", "dir.png"], "--plot: 'dir.png' is a directory"),
    (["--vary", GRID, "--output", ""], "--output: an empty file name"),
    ([*TWO, "--plot", ""], "--plot: an empty file name"),
    (["--vary", "initial/spin=1_0:20:2"], "--vary initial/spin: "),
    ([*TWO, "--output", "same.png", "--plot", "same.png"], "--output: 'same.png' has extension .png"),
    # Numbers of the run.
    (["--vary", GRID, "--workers", "-1"], "--workers: must be a whole number >= 1, got -1"),
    (["--vary", GRID, "--workers", "0"], "--workers: must be a whole number >= 1, got 0"),
    (["--vary", GRID, "--workers", "100000"], "--workers: at most 1024, got 100000"),
    (["--vary", GRID, "--batch-size", "0"], "--batch-size: must be a whole number >= 1, got 0"),
    (["--vary", GRID, "--batch-size", "-1"], "--batch-size: must be a whole number >= 1, got -1"),
    (["--vary", "initial/spin=0:1", "--design", "random", "--cases", "0"], "--cases: must be a whole number >= 1"),
    (["--vary", "initial/spin=0:1", "--design", "random", "--seed", "-1", "--cases", "2"], "--seed: must be"),
    (["--vary", "initial/spin=0:1", "--design", "random"], "--cases: a random design needs --cases N"),
    (["--vary", GRID, "--cases", "5"], "--cases: only for --design random or sobol"),
    (["--vary", GRID, "--seed", "5"], "--seed: only for --design random or sobol"),
    # Designs too large to hold, and values that are not finite numbers.
    (["--vary", "initial/spin=0:1:1e11"], "--vary: 1e+11 cases, more than the 1e+06 a sweep may run"),
    (["--vary", "initial/spin=0:1:1e6", "--vary", "initial/tilt=0:1:2"],
     "--vary: 2e+06 cases, more than the 1e+06 a sweep may run"),
    (["--vary", "initial/spin=0:1", "--design", "sobol", "--cases", "100000000000"],
     "--cases: 1e+11 cases, more than the 1e+06 a sweep may run"),
    (["--vary", "initial/spin=0:1:inf"], "--vary initial/spin: expected LOW:HIGH[:N] or V1,V2,... (finite numbers)"),
    (["--vary", "initial/spin=0:inf:3"], "--vary initial/spin: expected LOW:HIGH[:N] or V1,V2,... (finite numbers)"),
    (["--vary", "initial/spin=1,nan"], "--vary initial/spin: expected LOW:HIGH[:N] or V1,V2,... (finite numbers)"),
    # A key given twice: none silently wins.
    (["--vary", GRID, "--vary", "initial/spin=5,6"], "--vary initial/spin: given twice"),
    (["--vary", GRID, "--set", "initial/spin=4"], "--set initial/spin: also given by --vary"),
    (["--vary", GRID, "--set", "mass=0.1", "--set", "mass=0.2"], "--set mass: given twice"),
    # Options that would be ignored.
    (["--vary", GRID, "--x", "initial/spin"], "--x: only with --plot"),
    (["--vary", GRID, "--value", "final_tilt"], "--value: only with --plot"),
    ([*TWO, "--plot", "map.png", "--y", "initial/tilt", "--x", "initial/tilt"],
     "--y initial/tilt: the same key as --x"),
    (["--vary", GRID, "--scheduler", ""], "--scheduler: cannot connect to : not a scheduler address"),
    # The core's refusals, named by the option that gave the key.
    (["--vary", GRID, "--set", "mass=abc"], "--set: mass: 'abc' is not a number"),
    (["--vary", "initial/spinn=0:1:2"], "--vary: initial/spinn: unknown key"),
])
def test_refused_in_one_line_before_any_case_runs(sweep_main, arguments, message):
    status, err, ran = sweep_main(*arguments)
    assert status == 2
    assert len(err) == 1 and err[0].startswith(f"sweep: error: {message}"), err
    assert ran == 0


def test_a_sobol_design_of_other_than_a_power_of_2_warns_in_one_line(sweep_main):
    status, err, ran = sweep_main("--vary", "initial/spin=0:1", "--design", "sobol", "--cases", "3")
    assert (status, ran) == (0, 3)
    assert err[0] == "sweep: warning: --cases 3: Sobol points are balanced for a power of 2 cases (e.g. 2 or 4)"
    assert len(err) == 2 and err[1].startswith("sweep: 3 cases:")


def test_a_scene_file_value_is_refused_naming_config(sweep_main, tmp_path):
    scene = tmp_path / "bad.yaml"
    scene.write_text("scene: fixed_tip\nmass: abc\n")
    status, err, ran = sweep_main("--vary", GRID, config=scene)
    assert (status, ran) == (2, 0)
    assert err == [f"sweep: error: --config: {scene}: mass: 'abc' is not a number"]


def test_an_unreachable_scheduler_fails_at_once_in_one_line(sweep_main):
    with socket.socket() as s:  # a port nothing listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    status, err, _ = sweep_main("--vary", GRID, "--scheduler", f"tcp://127.0.0.1:{port}")
    assert status == 2
    assert err == [f"sweep: error: --scheduler: cannot connect to tcp://127.0.0.1:{port}: Connection refused"]


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="needs /dev/full")
def test_rows_that_cannot_be_written_are_kept_and_the_error_says_where(sweep_main, tmp_path):
    (tmp_path / "rows.csv").symlink_to("/dev/full")  # a name the sweep takes, on a full device
    status, err, ran = sweep_main("--vary", GRID, "--output", "rows.csv")
    assert (status, ran) == (2, 3)
    assert len(err) == 2 and err[1].startswith("sweep: 3 cases:"), err
    head, _, kept = err[0].partition("; the 3 rows are in ")
    assert head == "sweep: error: --output: cannot write 'rows.csv': No space left on device"
    assert os.path.dirname(kept) == str(tmp_path / "tmp")
    rows = pd.read_csv(kept)
    assert list(rows["initial/spin"]) == [0.0, 0.5, 1.0] and list(rows["outcome"]) == ["none"] * 3


def test_rows_on_a_failing_stdout_are_kept(sweep_main, monkeypatch, tmp_path):
    class Full:
        def write(self, text):
            raise OSError(28, "No space left on device")

        def flush(self):
            pass

    monkeypatch.setattr(sys, "stdout", Full())
    status, err, _ = sweep_main("--vary", GRID)
    assert status == 2
    assert err[0].startswith("sweep: error: --output: cannot write to stdout: No space left on device; "
                             f"the 3 rows are in {tmp_path / 'tmp'}")


def test_zero_cases_and_bad_run_arguments_are_refused_by_name():
    base = {"scene": "fixed_tip"}
    with pytest.raises(ValueError, match="^initial/spin: no values$"):
        sweep.design({"initial/spin": []})
    with pytest.raises(ValueError, match="^a sweep needs at least one case, got 0$"):
        sweep.run(base, {"initial/spin": np.array([])})
    with pytest.raises(ValueError, match="^workers: must be a whole number >= 1, got -1$"):
        sweep.run(base, {"initial/spin": np.array([1.0])}, workers=-1)
    with pytest.raises(ValueError, match="^batch_size: must be a whole number >= 1, got 0$"):
        sweep.run(base, {"initial/spin": np.array([1.0])}, batch_size=0)
    with pytest.raises(ValueError, match=r"^initial/spin: nan is not a finite number$"):
        sweep.design({"initial/spin": [1.0, float("nan")]})
    with pytest.raises(ValueError, match=r"^1e\+11 cases, more than the 1e\+06 a sweep may run"):
        sweep.design({"initial/spin": (0, 1, 10 ** 11)})


def test_an_unbounded_scene_file_is_one_line_naming_config(source_dir):
    # /dev/zero never ends: the core's reader refuses it (or, before it did, ran out of the
    # memory given here). Either way one line naming --config, no traceback.
    def limit_memory():
        resource.setrlimit(resource.RLIMIT_AS, (1 << 30, 1 << 30))  # a guard for the machine

    result = subprocess.run([sys.executable, "-m", "spinning_top.sweep", "--config", "/dev/zero", "--vary", GRID,
                             "--no-progress"], capture_output=True, text=True, timeout=300, preexec_fn=limit_memory)
    assert result.returncode == 2
    assert result.stderr.startswith("sweep: error: --config: ") and result.stderr.count("\n") == 1, result.stderr


def test_a_cluster_without_workers_is_refused_not_waited_on(monkeypatch):
    import faulthandler

    from distributed import LocalCluster

    faulthandler.dump_traceback_later(120, exit=True)  # a guard: the tasks used to wait forever
    monkeypatch.setattr(sweep, "WORKER_TIMEOUT", 0.5)
    with LocalCluster(n_workers=0, processes=False, dashboard_address=None) as cluster:
        with pytest.raises(ConnectionError, match=r"^the scheduler at \S+ has no workers \(none came within 0.5 s\)$"):
            sweep.run({"scene": "fixed_tip"}, {"initial/spin": np.array([1.0])}, scheduler=cluster.scheduler_address)
    faulthandler.cancel_dump_traceback_later()
