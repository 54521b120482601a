#!/usr/bin/env python3
"""Wall-clock pacing under load (issue 19, item 15): how far the node's ticks lag the wall clock
and how often its pacing diagnostics stay OK, on a quiet machine and beside two busy loops.
test/node_wall_clock.test asserts only what holds at any load (no tick dropped, none early,
exact /clock and tf decimation); the load-dependent figures are measured here.

The node runs at 1 kHz, real-time factor 1, use_sim_time false, on its own master. Its
/diagnostics (1 Hz) report the lag behind the wall clock at the end of each window and whether
the window was OK; this reads them with `rostopic echo` for WINDOW s per phase.

Usage: wall_clock_lag.py RESULTS_DIR [--quick]   (with build/devel/setup.bash sourced)
Writes wall_clock_lag.md into RESULTS_DIR.
"""
import os
import statistics
import subprocess
import sys
import threading
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from node_load import ROOT, free_port, wait_for_service  # noqa: E402


class PacingReports:
    """(level, lag [s]) of each 1 Hz diagnostics window of the node's own status."""

    def __init__(self, env):
        self.process = subprocess.Popen(["rostopic", "echo", "/diagnostics"], env=env, stdout=subprocess.PIPE,
                                        stderr=subprocess.DEVNULL, text=True, bufsize=1)
        self.samples = []
        self._level = None
        self._expect_lag = False
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self):
        for line in self.process.stdout:
            text = line.strip()
            if text.startswith("level:") and self._level is None:
                self._level = int(text.split()[-1].strip("\"'b\\x"), 0) if text.split()[-1].isdigit() else text
            elif 'key: "lag behind the wall clock [s]"' in text:
                self._expect_lag = True
            elif self._expect_lag and text.startswith("value:"):
                self.samples.append((self._level, float(text.split('"')[1])))
                self._expect_lag = False
            elif text == "---":
                self._level = None

    def take(self):
        samples, self.samples = self.samples, []
        return samples

    def stop(self):
        self.process.terminate()
        self.process.wait(timeout=10)


def summarize(phase, samples):
    lags = sorted(1e3 * lag for _, lag in samples)
    ok = sum(1 for level, _ in samples if level in (0, "0"))
    return (f"| {phase} | {len(samples)} | {ok} | {statistics.median(lags):.3f} | {lags[-1]:.3f} |"
            if lags else f"| {phase} | 0 | 0 | – | – |")


def main():
    results = sys.argv[1]
    window = 10.0 if "--quick" in sys.argv[2:] else 30.0
    env = dict(os.environ, ROS_MASTER_URI=f"http://127.0.0.1:{free_port()}")
    master = subprocess.Popen(["rosmaster", "--core", "-p", env["ROS_MASTER_URI"].rsplit(":", 1)[1]], env=env,
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    node = reports = None
    busy = []
    rows = []
    try:
        time.sleep(1.0)
        subprocess.run(["rosparam", "load", f"{ROOT}/config/fixed_tip.yaml", "/wall"], env=env, check=True)
        subprocess.run(["rosparam", "set", "/use_sim_time", "false"], env=env, check=True)
        node = subprocess.Popen([os.environ["SPINNING_TOP_NODE"], "__name:=wall", "_rate:=1000", "_real_time_factor:=1",
                                 "_publish_clock:=true"], env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        wait_for_service(env, "/wall/pause")
        reports = PacingReports(env)
        time.sleep(2.0)
        reports.take()
        time.sleep(window)
        rows.append(summarize("quiet", reports.take()))
        busy = [subprocess.Popen(["sh", "-c", "while :; do :; done"]) for _ in range(2)]
        time.sleep(window)
        rows.append(summarize("two busy loops", reports.take()))
    finally:
        for process in busy:
            process.kill()
        if reports is not None:
            reports.stop()
        for process in (node, master):
            if process is not None:
                process.terminate()
                process.wait(timeout=20)
    lines = ["| load | diagnostics windows | windows OK | median lag [ms] | max lag [ms] |", "|---|---|---|---|---|"]
    lines += rows
    lines += ["", f"`bench/wall_clock_lag.py`: the node at 1 kHz, real-time factor 1, wall-clock stamps, {window:g} s "
              "per phase; the lag behind the wall clock at the end of each 1 s diagnostics window, and the windows "
              "whose pacing status is OK (a sustained fraction of late ticks warns)."]
    with open(os.path.join(results, "wall_clock_lag.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
