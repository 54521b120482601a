#!/usr/bin/env python3
"""The node's CPU as launched, against a bare roscpp node beside it (issue 20, item 10).

Each row is one roslaunch on its own master: launch/spinning_top.launch as a user starts it
(1 kHz, use_sim_time true: the node publishes /clock), plus bench/bare_tf_node (one transform on
/tf from a 1 kHz WallTimer: the least a node that broadcasts a pose at 1 kHz does) in the same
graph, so that both pay the same ROS (the /clock every sim-time node receives, /rosout). The CPU
of each process (user + system, from /proc) over WINDOW wall seconds after a warm-up; the ratio
node / bare is the figure. Variants switch off one thing at a time to show what each costs.
Not a test: CPU depends on the machine and its load.

Usage: node_cpu.py RESULTS_DIR [--window 10] [--repeat 3] [--variants default,...]
       (with build/devel/setup.bash sourced, bare_tf_node built: scripts/bench.sh builds it)
Writes node_cpu.md into RESULTS_DIR.
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
from node_load import ROOT, cpu_seconds, free_port  # noqa: E402

# name: (launch args of spinning_top.launch, extra private parameters of the node, what it shows)
VARIANTS = {
    "default": ([], {}, "as `roslaunch spinning_top spinning_top.launch` starts it"),
    "no_clock": (["use_sim_time:=false"], {}, "use_sim_time false: no /clock, wall-clock stamps"),
    "clock_100": ([], {"clock_rate": 100}, "/clock at 100 Hz (~clock_rate)"),
}


def pid_of(name, parent):
    """The pid of the node `name` that roslaunch `parent` started (its child with that __name)."""
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                with open(f"/proc/{entry}/cmdline", "rb") as f:
                    arguments = f.read().split(b"\0")
                with open(f"/proc/{entry}/stat") as f:
                    ppid = int(f.read().rsplit(")", 1)[1].split()[1])
            except OSError:
                continue
            if ppid == parent and f"__name:={name}".encode() in arguments:
                return int(entry)
    return None


def launch_file(directory, arguments, parameters):
    args = "\n".join(f'    <arg name="{a.split(":=")[0]}" value="{a.split(":=")[1]}"/>' for a in arguments)
    params = "\n".join(f'    <param name="{k}" value="{v}"/>' for k, v in parameters.items())
    text = f"""<launch>
  <include file="{ROOT}/launch/spinning_top.launch">
{args}
  </include>
  <group ns="spinning_top">
{params}
  </group>
  <node name="bare_tf_node" pkg="spinning_top" type="bare_tf_node"/>
</launch>
"""
    path = os.path.join(directory, "node_cpu.launch")
    with open(path, "w") as f:
        f.write(text)
    return path


def measure(variant, window, warm_up):
    arguments, parameters, _ = VARIANTS[variant]
    port = free_port()
    env = dict(os.environ, ROS_MASTER_URI=f"http://127.0.0.1:{port}", ROS_HOSTNAME="127.0.0.1")
    with tempfile.TemporaryDirectory() as directory:
        path = launch_file(directory, arguments, parameters)
        log = open(os.path.join(directory, "roslaunch.log"), "w")
        launch = subprocess.Popen(["roslaunch", "-p", str(port), path], env=env, stdout=log,
                                  stderr=subprocess.STDOUT, start_new_session=True)
        try:
            deadline = time.monotonic() + 60
            pids = {}
            while len(pids) < 2:
                if time.monotonic() > deadline or launch.poll() is not None:
                    log.close()
                    with open(log.name) as f:
                        raise RuntimeError(f"{variant}: the nodes did not start:\n" + f.read()[-2000:])
                time.sleep(0.5)
                for name in ("spinning_top", "bare_tf_node"):
                    pid = pid_of(name, launch.pid)
                    if pid is not None:
                        pids[name] = pid
            time.sleep(warm_up)
            start = {name: cpu_seconds(pid) for name, pid in pids.items()}
            t0 = time.monotonic()
            time.sleep(window)
            elapsed = time.monotonic() - t0
            return {name: 100.0 * (cpu_seconds(pid) - start[name]) / elapsed for name, pid in pids.items()}
        finally:
            try:
                os.killpg(launch.pid, signal.SIGINT)
                launch.wait(timeout=30)
            except ProcessLookupError:
                pass
            except subprocess.TimeoutExpired:
                os.killpg(launch.pid, signal.SIGKILL)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("results")
    parser.add_argument("--window", type=float, default=10.0)
    parser.add_argument("--warm-up", type=float, default=3.0)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--variants", default=",".join(VARIANTS))
    options = parser.parse_args()
    variants = options.variants.split(",")
    for variant in variants:
        if variant not in VARIANTS:
            parser.error(f"--variants: no variant {variant!r}; one of {', '.join(VARIANTS)}")
    samples = {variant: [] for variant in variants}
    for _ in range(options.repeat):  # interleaved, so that a change of load hits every variant
        for variant in variants:
            cpu = measure(variant, options.window, options.warm_up)
            samples[variant].append(cpu)
            print(f"node_cpu: {variant}: node {cpu['spinning_top']:.1f} %, bare {cpu['bare_tf_node']:.1f} %, "
                  f"ratio {cpu['spinning_top'] / cpu['bare_tf_node']:.2f}", flush=True)
    os.makedirs(options.results, exist_ok=True)
    with open(os.path.join(options.results, "node_cpu.md"), "w") as f:
        f.write("| variant | node CPU [% of a core] | bare node beside it [%] | node / bare (median of runs) | runs |\n"
                "|---|---|---|---|---|\n")
        for variant in variants:
            runs = samples[variant]
            node = statistics.median(r["spinning_top"] for r in runs)
            bare = statistics.median(r["bare_tf_node"] for r in runs)
            ratio = statistics.median(r["spinning_top"] / r["bare_tf_node"] for r in runs)
            f.write(f"| {variant}: {VARIANTS[variant][2]} | {node:.1f} | {bare:.1f} | {ratio:.2f} | {len(runs)} |\n")
        f.write(f"\n`bench/node_cpu.py`: one roslaunch per run on its own master, the shipped launch file and "
                f"bench/bare_tf_node side by side, {options.window:g} s windows after {options.warm_up:g} s, runs "
                f"interleaved; {time.strftime('%Y-%m-%d')}, load {os.getloadavg()[0]:.1f} at the end.\n")


if __name__ == "__main__":
    main()
