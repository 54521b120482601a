#!/usr/bin/env python3
"""Spawning and stopping a node with many tops (issue 19, item 5): what one ~spawn costs as the
count of tops grows, and how long the node takes to exit at SIGINT.

The node runs on its own master (roscore on a free port), 1 kHz, real-time factor 1 (or paused
with --paused). A persistent rospy service proxy calls ~spawn COUNT times (fixed-tip tops on a
grid); each call's wall time is recorded. Then SIGINT: the time until the process has exited,
with the node's own account of its unregistration (its log line).
test/node_many_tops.test asserts what holds at any load (a spawn does the same work whatever the
count; exit code 0 at SIGINT); the wall times, which depend on the machine, are measured here.

--per-top chooses what each spawned top registers with the master (repeat it to compare, runs
interleaved): a comma list of its topics (~spawn_topics) and `reset` (its ~<name>/reset service,
~spawn_reset_services); `none` (the node's default, and this script's) nothing, `all` the seven
topics and the service.

--bare runs bench/bare_spawner beside each configuration, the same way: a roscpp node whose
~spawn makes only the spawn's calls to the master (the top's topics, its reset service, its URDF
parameter) and simulates nothing. Its growth with the count is roscpp's and rosmaster's own;
what the node's spawn adds to it is the node's.

Usage: node_scale.py RESULTS_DIR [--count 1000] [--paused | --also-paused] [--repeat 1] [--per-top SPEC ...] [--bare]
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


def executable(name="spinning_top_node"):
    for directory in os.environ.get("CMAKE_PREFIX_PATH", "").split(":"):
        candidate = os.path.join(directory, "lib", "spinning_top", name)
        if os.path.exists(candidate):
            return candidate
    hint = " (cmake --build build --target bare_spawner)" if name == "bare_spawner" else ""
    raise SystemExit(f"node_scale.py: error: no {name} found{hint}: source build/devel/setup.bash first")


ALL_TOPICS = ["contact_point", "normal_force", "twist", "state", "markers", "event", "event_stamped"]


def per_top_arguments(spec):
    """The node's arguments for a --per-top SPEC, and the registrations per top it makes."""
    names = (ALL_TOPICS + ["reset"] if spec == "all" else [] if spec == "none"
             else [n.strip() for n in spec.split(",") if n.strip()])
    unknown = [n for n in names if n not in ALL_TOPICS + ["reset"]]
    if unknown:
        raise SystemExit(f"node_scale.py: error: --per-top: unknown {unknown} (topics {ALL_TOPICS}, reset)")
    topics = [n for n in names if n != "reset"]
    # Both always given: the bare spawner's defaults follow the node's, but a row says what it ran.
    arguments = [f"_spawn_topics:=[{','.join(topics)}]",
                 f"_spawn_reset_services:={'true' if 'reset' in names else 'false'}"]
    return arguments, len(names)


def run(count, paused, log_lines, per_top=(), program="spinning_top_node"):
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
        arguments = [executable(program), "__name:=scale", "_rate:=1000", f"_start_paused:={str(paused).lower()}",
                     *per_top]
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
    parser.add_argument("--paused", action="store_true", help="spawn into a paused node only")
    parser.add_argument("--also-paused", action="store_true", help="each run also into a paused node")
    parser.add_argument("--repeat", type=int, default=1, help="runs of each --per-top (default 1)")
    parser.add_argument("--bare", action="store_true",
                        help="also run bench/bare_spawner (the spawn's master calls only) in each configuration")
    parser.add_argument("--per-top", action="append", metavar="SPEC",
                        help="what each spawned top registers: none (default), all, or a comma list of its "
                             "topics and reset (its service); repeat it to compare")
    options = parser.parse_args()
    specs = options.per_top or ["none"]
    modes = [True] if options.paused else [False, True] if options.also_paused else [False]
    programs = ["spinning_top_node", "bare_spawner"] if options.bare else ["spinning_top_node"]
    for program in programs:
        executable(program)  # before any run
    # The bare spawner has no pause: once per SPEC, after the node's first mode.
    configurations = [(program, paused, spec, *per_top_arguments(spec))
                      for paused in modes for spec in specs for program in programs
                      if program == "spinning_top_node" or paused == modes[0]]
    os.makedirs(options.results, exist_ok=True)
    lines = []
    for run_index in range(options.repeat):
        for program, paused, spec, arguments, registrations in configurations:
            log = os.path.join(tempfile.gettempdir(), "node_scale_node.log")  # the node's own lines
            costs, exit_seconds, code = run(options.count, paused, log, arguments, program)
            tenth = max(1, len(costs) // 10)
            first = statistics.median(costs[:tenth]) * 1e3
            last = statistics.median(costs[-tenth:]) * 1e3
            with open(log) as f:
                account = [line.strip() for line in f if "unregister" in line or "exit" in line.lower() or "master did not" in line]
            node = ("paused" if paused else "running") if program == "spinning_top_node" else "bare_spawner"
            lines.append(f"| {options.count} | {node} | {spec} ({registrations}) "
                         f"| {first:.1f} | {last:.1f} | "
                         f"{sum(costs):.1f} | {exit_seconds:.2f} | {code} |")
            print(lines[-1], *account, sep="\n  ", flush=True)
    with open(os.path.join(options.results, "node_scale.md"), "w") as f:
        f.write(f"{time.strftime('%Y-%m-%d %H:%M')}, load {os.getloadavg()[0]:.1f}\n\n"
                "| tops spawned | node | per top (registrations) | first 10 % of spawns, median [ms] | last 10 % [ms] "
                "| all spawns [s] | SIGINT to exit [s] | exit code |\n|---|---|---|---|---|---|---|---|\n")
        f.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
