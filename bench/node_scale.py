#!/usr/bin/env python3
"""Spawning and stopping a node with many tops (issue 19, item 5): what one ~spawn costs as the
count of tops grows, and how long the node takes to exit at SIGINT.

The node runs on its own master (roscore on a free port), 1 kHz, real-time factor 1 (or paused
with --paused). A persistent rospy service proxy calls ~spawn COUNT times (fixed-tip tops on a
grid); each call's wall time is recorded. Then SIGINT: the time until the process has exited,
with the node's own account of its unregistration (its log line).
test/node_many_tops.test asserts what holds at any load (a spawn does the same work whatever the
count; exit code 0 at SIGINT); the wall times, which depend on the machine, are measured here.

Usage: node_scale.py RESULTS_DIR [--count 1000] [--paused] [--repeat 1]
       (with build/devel/setup.bash sourced; /usr/bin/python3)
Writes node_scale.md into RESULTS_DIR.
"""
import argparse
import os
import signal
import statistics
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from node_load import free_port, wait_for_service  # noqa: E402


def node_executable():
    for directory in os.environ.get("CMAKE_PREFIX_PATH", "").split(":"):
        candidate = os.path.join(directory, "lib", "spinning_top", "spinning_top_node")
        if os.path.exists(candidate):
            return candidate
    raise SystemExit("node_scale.py: error: no spinning_top_node found: source build/devel/setup.bash first")


def run(count, paused, log_lines):
    port = free_port()
    env = dict(os.environ, ROS_MASTER_URI=f"http://127.0.0.1:{port}", ROS_HOSTNAME="127.0.0.1")
    env.pop("ROS_IP", None)
    roscore = subprocess.Popen(["roscore", "-p", str(port)], env=env, stdout=subprocess.DEVNULL,
                               stderr=subprocess.DEVNULL, start_new_session=True)
    node = None
    try:
        os.environ.update(ROS_MASTER_URI=env["ROS_MASTER_URI"], ROS_HOSTNAME="127.0.0.1")
        import rospy
        from spinning_top.srv import Spawn

        deadline = time.monotonic() + 30
        while subprocess.run(["rosparam", "list"], env=env, capture_output=True).returncode != 0:
            if time.monotonic() > deadline:
                raise RuntimeError("roscore did not come up")
            time.sleep(0.2)
        arguments = [node_executable(), "__name:=scale", "_rate:=1000", f"_start_paused:={str(paused).lower()}"]
        log = open(log_lines, "w")
        node = subprocess.Popen(arguments, env=env, stdout=log, stderr=subprocess.STDOUT)
        wait_for_service(env, "/scale/spawn")
        spawn = rospy.ServiceProxy("/scale/spawn", Spawn, persistent=True)
        costs = []
        for i in range(count):
            start = time.perf_counter()
            response = spawn(name=f"s{i:04d}", scene_file="", keys=["after_lift_off=stop"],
                             x=0.05 * (i % 40), y=0.05 * (i // 40))
            costs.append(time.perf_counter() - start)
            if not response.success:
                raise RuntimeError(response.message)
        spawn.close()
        start = time.perf_counter()
        node.send_signal(signal.SIGINT)
        code = node.wait(timeout=120)
        exit_seconds = time.perf_counter() - start
        log.close()
        return costs, exit_seconds, code
    finally:
        if node is not None and node.poll() is None:
            node.kill()
        os.killpg(roscore.pid, signal.SIGINT)
        roscore.wait(timeout=30)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("results", help="directory for node_scale.md")
    parser.add_argument("--count", type=int, default=1000, help="tops to spawn (default 1000)")
    parser.add_argument("--paused", action="store_true", help="spawn into a paused node")
    parser.add_argument("--repeat", type=int, default=1, help="runs (default 1)")
    options = parser.parse_args()
    os.makedirs(options.results, exist_ok=True)
    lines = []
    for run_index in range(options.repeat):
        log = os.path.join(tempfile.gettempdir(), "node_scale_node.log")  # the node's own lines
        costs, exit_seconds, code = run(options.count, options.paused, log)
        tenth = max(1, len(costs) // 10)
        first = statistics.median(costs[:tenth]) * 1e3
        last = statistics.median(costs[-tenth:]) * 1e3
        with open(log) as f:
            account = [line.strip() for line in f if "unregister" in line or "exit" in line.lower() or "master did not" in line]
        lines.append(f"| {options.count} | {'paused' if options.paused else 'running'} | {first:.1f} | {last:.1f} | "
                     f"{sum(costs):.1f} | {exit_seconds:.2f} | {code} |")
        print(lines[-1], *account, sep="\n  ", flush=True)
    with open(os.path.join(options.results, "node_scale.md"), "w") as f:
        f.write(f"{time.strftime('%Y-%m-%d %H:%M')}, load {os.getloadavg()[0]:.1f}\n\n"
                "| tops spawned | node | first 10 % of spawns, median [ms] | last 10 % [ms] | all spawns [s] "
                "| SIGINT to exit [s] | exit code |\n|---|---|---|---|---|---|---|\n")
        f.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
