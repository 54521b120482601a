#!/usr/bin/env python3
"""Message loss of `roslaunch spinning_top spinning_top.launch record:=true` (issue 20, item 11).

Each run starts its own master (a free port, a fresh ROS_HOME), `busy` CPU-bound shell loops at
the same priority as ROS (`while :; do :; done`), then the launch file with record:=true at
`rate` Hz, lets it record for `seconds` of wall time after the first tick and stops it with
SIGINT. It then reads the bag: every 1-per-tick topic (/clock, /tf, ~contact_point,
~normal_force, ~twist, ~state) should hold one message per tick from its first to its last, so
each missing tick is a lost message, and consecutive ones are a gap. Where they were lost is
read from the logs, with roscpp's DEBUG messages switched on for both processes (they are
silent otherwise):
  "Outgoing queue full for topic"    the node's publisher queue (advertise's queue size),
  "Incoming queue was full for topic" the recorder's subscriber queue (100, fixed in rosbag),
  "rosbag record buffer exceeded"    the recorder's write buffer (--buffsize),
and the node's own "ticks given up" (~max_lag) and the recorder's "lost" diagnostics.

Usage (with build/devel/setup.bash sourced; CPU-bound: run it under the build lock):
  record_loss.py RESULTS_DIR [--runs N] [--seconds 14] [--busy 2] [--rate 1000] [--label NAME]
                 [--stall node|record --stall-ms 200 --stall-every 2] [--keep] [-- launch args]
  record_loss.py --check BAG [--rate 1000]   only the ticks missing in a bag (exit 1 if any)
Appends one row per run to RESULTS_DIR/record_loss.csv and writes RESULTS_DIR/record_loss_<label>.md.
"""
import argparse
import collections
import csv
import datetime
import glob
import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time

PER_TICK = ("/clock", "/tf", "contact_point", "normal_force", "twist", "state")
LOG_PATTERNS = {
    "node_outgoing_full": re.compile(r"Outgoing queue full for topic \[?([^\]. ]+)"),
    # roscpp's own /clock subscription (queue size 1, "current queue size [0]") reports this at
    # every /clock message that arrives before the last was used: not a loss; only longer queues.
    "recorder_incoming_full": re.compile(r'Incoming queue was full for topic "([^"]+)"\. Discarded oldest '
                                         r'message \(current queue size \[(?!0\])'),
    "recorder_buffer_exceeded": re.compile(r"rosbag record buffer exceeded"),
    "node_ticks_given_up": re.compile(r"ticks given up"),
}
ROSCONSOLE = """log4j.logger.ros=INFO
log4j.logger.ros.roscpp=DEBUG
log4j.logger.ros.roscpp.superdebug=WARN
log4j.logger.ros.roscpp.cached_parameters=WARN
"""


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def tick_times(bag_path, node):
    """{topic: [simulated time of each message in bag order]} for the per-tick topics."""
    import rosbag  # the system's, with the devel space sourced

    # The launch file gives the recorder relative names, which rosbag keeps as given
    # (spinning_top/state); absolute ones (/spinning_top/state) from other recorders.
    names = {}
    for t in PER_TICK:
        for name in ([t] if t.startswith("/") else [f"/{node}/{t}", f"{node}/{t}"]):
            names[name] = t
    times = collections.defaultdict(list)
    with rosbag.Bag(bag_path) as bag:
        for topic, message, _ in bag.read_messages(topics=list(names)):
            if topic == "/clock":
                stamp = message.clock
            elif topic == "/tf":
                stamp = message.transforms[0].header.stamp
            else:
                stamp = message.header.stamp
            times[names[topic]].append(stamp.to_sec())
    return times


def gaps(seconds, rate):
    """(count, missing ticks, [(first missing tick, length)], duplicates) over first..last."""
    ticks = sorted(round(t * rate) for t in seconds)
    if not ticks:
        return 0, 0, [], 0
    runs, duplicates = [], 0
    for a, b in zip(ticks, ticks[1:]):
        if b == a:
            duplicates += 1
        elif b > a + 1:
            runs.append((a + 1, b - a - 1))
    return len(ticks), sum(n for _, n in runs), runs, duplicates


def process_of(which, ros_home, launch_pid):
    """The pid of the node (`node`) or of the recorder (`record`) that roslaunch started."""
    executable = {"node": "spinning_top_node", "record": "record"}[which]
    children = subprocess.run(["pgrep", "-P", str(launch_pid)], capture_output=True, text=True).stdout.split()
    for pid in children:
        with open(f"/proc/{pid}/cmdline", "rb") as f:
            argv0 = f.read().split(b"\0")[0].decode()
        if os.path.basename(argv0) == executable:
            return int(pid)
    raise RuntimeError(f"no {executable} among roslaunch's children {children}")


def run_once(args, extra, work):
    port = free_port()
    env = dict(os.environ, ROS_MASTER_URI=f"http://localhost:{port}", ROS_HOME=os.path.join(work, "ros"))
    if args.debug:
        with open(os.path.join(work, "rosconsole.config"), "w") as f:
            f.write(ROSCONSOLE)
        env["ROSCONSOLE_CONFIG_FILE"] = os.path.join(work, "rosconsole.config")
    bag = os.path.join(work, "run.bag")
    busy = [subprocess.Popen(["sh", "-c", "while :; do :; done"]) for _ in range(args.busy)]
    launch_log = open(os.path.join(work, "launch.log"), "w")
    launch = subprocess.Popen(["roslaunch", "-p", str(port), "spinning_top", "spinning_top.launch", "record:=true",
                               f"bag:={bag}", f"rate:={args.rate}", *extra],
                              env=env, stdout=launch_log, stderr=subprocess.STDOUT, start_new_session=True)
    try:
        deadline = time.monotonic() + 120
        started = None
        while time.monotonic() < deadline and launch.poll() is None:
            with open(launch_log.name) as f:
                if "the simulation starts" in f.read():
                    started = time.monotonic()
                    break
            time.sleep(0.1)
        if started is None:
            raise RuntimeError(f"the node did not start ticking; see {launch_log.name}")
        if args.stall:
            # A machine's hiccup, made on purpose: the process stopped for stall_ms (SIGSTOP), then
            # resumed; the node catches up by the ticks it missed, in one burst.
            pid = process_of(args.stall, env["ROS_HOME"], launch.pid)
            end = started + args.seconds
            while time.monotonic() + args.stall_every < end:
                time.sleep(args.stall_every)
                os.kill(pid, signal.SIGSTOP)
                time.sleep(args.stall_ms / 1000.0)
                os.kill(pid, signal.SIGCONT)
            time.sleep(max(0.0, end - time.monotonic()))
        else:
            time.sleep(args.seconds)
    finally:
        os.killpg(launch.pid, signal.SIGINT)
        try:
            launch.wait(timeout=60)
        except subprocess.TimeoutExpired:
            os.killpg(launch.pid, signal.SIGKILL)
            launch.wait()
        for p in busy:
            p.kill()
            p.wait()
        launch_log.close()
    logs = [launch_log.name] + glob.glob(os.path.join(env["ROS_HOME"], "log", "**", "*.log"), recursive=True)
    found = collections.Counter()
    lines = collections.defaultdict(list)
    for path in logs:
        with open(path, errors="replace") as f:
            for line in f:
                for key, pattern in LOG_PATTERNS.items():
                    if pattern.search(line):
                        found[key] += 1
                        if len(lines[key]) < 5:
                            lines[key].append(line.strip()[:200])
    if not os.path.exists(bag):
        active = bag + ".active"
        raise RuntimeError(f"no bag ({'only ' + active if os.path.exists(active) else 'nothing'} in {work})")
    return tick_times(bag, args.node_name), found, lines


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("results", nargs="?", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), "results"))
    parser.add_argument("--runs", type=int, default=1)
    parser.add_argument("--seconds", type=float, default=14.0)
    parser.add_argument("--busy", type=int, default=2)
    parser.add_argument("--rate", type=float, default=1000.0)
    parser.add_argument("--label", default="main")
    parser.add_argument("--node-name", default="spinning_top")
    parser.add_argument("--no-debug", dest="debug", action="store_false",
                        help="leave roscpp's DEBUG messages off (they name the queue that dropped)")
    parser.add_argument("--keep", action="store_true", help="keep the bags and logs (printed)")
    parser.add_argument("--stall", choices=["node", "record"],
                        help="stop that process for --stall-ms every --stall-every s (SIGSTOP, SIGCONT)")
    parser.add_argument("--stall-ms", type=float, default=200.0)
    parser.add_argument("--stall-every", type=float, default=2.0)
    parser.add_argument("--check", metavar="BAG", help="only report the ticks missing in an existing bag")
    args, extra = parser.parse_known_args()
    if args.check:
        times = tick_times(args.check, args.node_name)
        lost = 0
        for topic in PER_TICK:
            count, missing, runs, _ = gaps(times.get(topic, []), args.rate)
            lost += missing
            print(f"{topic}: {count} messages, {missing} ticks missing"
                  + (f" in {len(runs)} gaps (first tick: length) " + ", ".join(f"{a}: {n}" for a, n in runs[:10])
                     if runs else ""))
        sys.exit(1 if lost else 0)
    extra = [a for a in extra if a != "--"]
    os.makedirs(args.results, exist_ok=True)
    rows, report = [], []
    for run in range(1, args.runs + 1):
        work = tempfile.mkdtemp(prefix="record_loss_")
        try:
            times, found, lines = run_once(args, extra, work)
        finally:
            if args.keep:
                print(f"record_loss: kept {work}", file=sys.stderr)
            else:
                shutil.rmtree(work, ignore_errors=True)
        report.append(f"### run {run}\n")
        report.append("| topic | messages | missing | gaps (first tick: length) | duplicates |")
        report.append("|---|---|---|---|---|")
        total_missing = 0
        for topic in PER_TICK:
            count, missing, runs, duplicates = gaps(times.get(topic, []), args.rate)
            total_missing += missing
            shown = ", ".join(f"{a}: {n}" for a, n in runs[:6]) + (" ..." if len(runs) > 6 else "")
            report.append(f"| {topic} | {count} | {missing} ({100.0 * missing / max(count + missing, 1):.2f} %) "
                          f"| {shown or '-'} | {duplicates} |")
            rows.append({"label": args.label, "run": run, "rate": args.rate, "busy": args.busy,
                         "seconds": args.seconds, "extra": " ".join(extra), "topic": topic, "messages": count,
                         "missing": missing, "gaps": len(runs), "longest_gap": max((n for _, n in runs), default=0),
                         **{key: found.get(key, 0) for key in LOG_PATTERNS}})
        report.append("")
        report.append("Logs: " + (", ".join(f"{k} x{v}" for k, v in sorted(found.items())) or "no loss reported"))
        for key, sample in sorted(lines.items()):
            report += [f"    {key}: {line}" for line in sample[:2]]
        report.append("")
        print("\n".join(report[-(len(PER_TICK) + 6 + sum(min(len(v), 2) for v in lines.values())):]))
        sys.stdout.flush()
    csv_path = os.path.join(args.results, "record_loss.csv")
    new = not os.path.exists(csv_path)
    with open(csv_path, "a", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        if new:
            writer.writeheader()
        writer.writerows(rows)
    header = [f"# record_loss: {args.label}", "",
              f"{datetime.datetime.now().isoformat(timespec='seconds')}, {os.uname().nodename}, "
              f"{os.cpu_count()} cores; `spinning_top.launch record:=true rate:={args.rate:g} {' '.join(extra)}`, "
              f"{args.seconds:g} s after the first tick, {args.busy} busy loops at the same priority, "
              + (f"the {args.stall} stopped for {args.stall_ms:g} ms every {args.stall_every:g} s, " if args.stall else "")
              + f"roscpp DEBUG {'on' if args.debug else 'off'}.", ""]
    with open(os.path.join(args.results, f"record_loss_{args.label}.md"), "w") as f:
        f.write("\n".join(header + report) + "\n")


if __name__ == "__main__":
    main()
