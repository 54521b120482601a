#!/usr/bin/env python3
"""The node's cost (issue 9): CPU of spinning_top_node at 1 kHz with one and with five tops, and
ticks per second at real_time_factor 0, per scene. Each case starts its own master on a free
port and its own node, warms up, then reads the node's CPU time (/proc/PID/stat) over a window
of wall time with no subscriber, then the ticks per second over a second window from the world
time the node reports in /diagnostics. Writes node_load.md and node_load.csv into the results folder.

Usage: node_load.py RESULTS_DIR [--quick]   (with build/devel/setup.bash sourced)
"""
import csv
import os
import re
import socket
import subprocess
import sys
import threading
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TICKS_PER_SECOND = os.sysconf("SC_CLK_TCK")


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def cpu_seconds(pid):
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / TICKS_PER_SECOND  # utime + stime


def wait_for_service(env, name, timeout=30.0):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if subprocess.run(["rosservice", "list"], env=env, capture_output=True, text=True).stdout.count(name):
            return
        time.sleep(0.2)
    raise RuntimeError(f"{name} did not come up")


class WorldTimes:
    """The world's simulated time as the node reports it in /diagnostics (1 Hz), with the wall
    time each report arrived: costs the node nothing it does not do anyway (a /clock subscriber
    at 1 kHz would, and ~pause/~resume would stop it)."""

    def __init__(self, env):
        self.process = subprocess.Popen(["rostopic", "echo", "/diagnostics"], env=env, stdout=subprocess.PIPE,
                                        stderr=subprocess.DEVNULL, text=True, bufsize=1)
        self.samples = []
        self.thread = threading.Thread(target=self._read, daemon=True)
        self.thread.start()

    def _read(self):
        expect_value = False
        for line in self.process.stdout:
            if 'key: "world time [s]"' in line:
                expect_value = True
            elif expect_value and "value:" in line:
                self.samples.append((time.monotonic(), float(line.split('"')[1])))
                expect_value = False

    def stop(self):
        self.process.terminate()
        self.process.wait(timeout=10)
        return list(self.samples)


def measure(scene, tops, real_time_factor, window, warm_up):
    env = dict(os.environ, ROS_MASTER_URI=f"http://127.0.0.1:{free_port()}")
    master = subprocess.Popen(["rosmaster", "--core", "-p", env["ROS_MASTER_URI"].rsplit(":", 1)[1]], env=env,
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    node = None
    try:
        time.sleep(1.0)
        subprocess.run(["rosparam", "load", f"{ROOT}/config/{scene}.yaml", "/bench"], env=env, check=True)
        subprocess.run(["rosparam", "set", "/use_sim_time", "true"], env=env, check=True)
        if tops > 1:
            names = [f"top{i}" for i in range(tops)]
            subprocess.run(["rosparam", "set", "/bench/tops", "[" + ", ".join(names) + "]"], env=env, check=True)
            for i, name in enumerate(names):  # spins 60..160 rad/s, 0.1 m apart
                subprocess.run(["rosparam", "set", f"/bench/{name}/initial/spin", str(60.0 + 25.0 * i)], env=env,
                               check=True)
                subprocess.run(["rosparam", "set", f"/bench/{name}/x", str(0.1 * i)], env=env, check=True)
        node = subprocess.Popen([f"{os.environ['SPINNING_TOP_NODE']}", "__name:=bench", "_rate:=1000",
                                 f"_real_time_factor:={real_time_factor}"], env=env,
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        wait_for_service(env, "/bench/pause")
        time.sleep(warm_up)
        # CPU first, with no subscriber at all (one to /diagnostics measurably raised the node's
        # CPU at 1 kHz, from ~15 % to ~25 % of a core); then the ticks, over a second window.
        t0, c0 = time.monotonic(), cpu_seconds(node.pid)
        time.sleep(window)
        t1, c1 = time.monotonic(), cpu_seconds(node.pid)
        world = WorldTimes(env)
        time.sleep(window + 2.0)
        samples = world.stop()
        if len(samples) < 2:
            raise RuntimeError("fewer than two diagnostics in the window")
        (w0, s0), (w1, s1) = samples[0], samples[-1]
        ticks_per_second = 1000.0 * (s1 - s0) / (w1 - w0)
        # CPU per tick at the pace the CPU window ran (the ticks are measured just after it).
        return {"scene": scene, "tops": tops, "real_time_factor": real_time_factor,
                "cpu_percent": 100.0 * (c1 - c0) / (t1 - t0),
                "ticks_per_second": ticks_per_second,
                "cpu_per_tick_us": 1e6 * (c1 - c0) / (t1 - t0) / ticks_per_second}
    finally:
        for process in (node, master):
            if process is not None:
                process.terminate()
                process.wait(timeout=20)


def main():
    results = sys.argv[1]
    quick = "--quick" in sys.argv[2:]
    window, warm_up = (3.0, 1.0) if quick else (10.0, 2.0)
    rows = []
    for scene in ("fixed_tip", "viscous"):
        for tops, factor in ((1, 1), (5, 1), (1, 0)):
            row = measure(scene, tops, factor, window, warm_up)
            rows.append(row)
            print(f"node_load: {scene}, {tops} top(s), real-time factor {factor}: {row['cpu_percent']:.1f} % CPU, "
                  f"{row['ticks_per_second']:.0f} ticks/s, {row['cpu_per_tick_us']:.1f} us CPU per tick", flush=True)
    with open(os.path.join(results, "node_load.csv"), "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    lines = ["| scene | tops | real-time factor | node CPU [% of a core] | ticks per wall s | CPU per tick [µs] |",
             "|---|---|---|---|---|---|"]
    for r in rows:
        factor = "0 (as fast as possible)" if r["real_time_factor"] == 0 else str(r["real_time_factor"])
        lines.append(f"| {r['scene']} | {r['tops']} | {factor} | {r['cpu_percent']:.1f} | "
                     f"{r['ticks_per_second']:,.0f} | {r['cpu_per_tick_us']:.1f} |")
    lines.append("")
    lines.append(f"`bench/node_load.py`: 1 kHz, default scene files, {window:g} s of wall time per row after "
                 f"{warm_up:g} s of warm-up; CPU from /proc (user + system) of the node process with no subscriber; five "
                 "tops spin at 60–160 rad/s. Ticks per wall second from the world's simulated time in /diagnostics, "
                 "over the next window.")
    with open(os.path.join(results, "node_load.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
