#!/usr/bin/env python3
"""Before against after, in one run: the CPU of two builds of the core on the same benchmarks,
interleaved (A, B, A, B, ...) so that both see the same load, as ratios B / A.

Runs `work_precision --quick` (every integrator's work-precision points and the default's state
every 1 ms) and `node_load.py --quick` (the node at 1 kHz and as fast as possible) for each build,
`--rounds` times each (in the order A, B, B, A, A, B, ...), and reports the median ratio per method and overall. A ratio of 1.00 is
no change; the spread between rounds of the same build says what counts as measurable.

Usage: ab_compare.py OLD_DEVEL_LIB NEW_DEVEL_LIB OUTPUT.md [--rounds N] [--no-node]
  *_DEVEL_LIB: a build's devel/lib folder (holding spinning_top/work_precision,
  spinning_top/spinning_top_node and the core's shared libraries). A build's devel/lib can be
  copied elsewhere first: its binaries find their libraries through LD_LIBRARY_PATH.
  With build/devel/setup.bash sourced (node_load.py needs roscore and rostopic).
"""
import csv
import os
import statistics
import subprocess
import sys
import tempfile
from collections import defaultdict

HERE = os.path.dirname(os.path.abspath(__file__))


def run_work_precision(lib, out_dir):
    os.makedirs(out_dir, exist_ok=True)
    env = dict(os.environ, LD_LIBRARY_PATH=lib)
    subprocess.run([os.path.join(lib, "spinning_top", "work_precision"), "--quick", "--output-dir", out_dir], env=env,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True)
    rows = {}
    with open(os.path.join(out_dir, "work_precision.csv")) as f:
        for r in csv.DictReader(f):
            if r["family"] == "ours":
                rows[("work_precision", r["scene"], r["method"], r["parameter"])] = float(r["cpu_seconds"])
    with open(os.path.join(out_dir, "dense_sampling.csv")) as f:
        for r in csv.DictReader(f):
            if r["family"] in ("ours", "default"):
                rows[("dense_sampling", r["scene"], r["method"], r["setting"])] = float(r["cpu_seconds"])
    return rows


def run_node_load(lib, out_dir):
    os.makedirs(out_dir, exist_ok=True)
    env = dict(os.environ, LD_LIBRARY_PATH=lib, SPINNING_TOP_NODE=os.path.join(lib, "spinning_top", "spinning_top_node"))
    subprocess.run(["/usr/bin/python3", os.path.join(HERE, "node_load.py"), out_dir, "--quick"], env=env,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True)
    rows = {}
    with open(os.path.join(out_dir, "node_load.csv")) as f:
        for r in csv.DictReader(f):
            key = ("node_load", r["scene"], f"{r['tops']} tops", f"real-time factor {r['real_time_factor']}")
            # CPU per tick: comparable whatever the tick rate reached.
            rows[key] = float(r["cpu_per_tick_us"])
    return rows


def main(argv):
    if len(argv) < 4:
        print(__doc__, file=sys.stderr)
        return 2
    old, new, output = (os.path.abspath(a) for a in argv[1:4])
    rounds = int(argv[argv.index("--rounds") + 1]) if "--rounds" in argv else 4
    with_node = "--no-node" not in argv
    samples = {"old": defaultdict(list), "new": defaultdict(list)}
    with tempfile.TemporaryDirectory() as tmp:
        for k in range(rounds):
            # ABBA: the order alternates, so that a drift of the machine over the run (load,
            # frequency) does not favour the build that runs first.
            order = (("old", old), ("new", new)) if k % 2 == 0 else (("new", new), ("old", old))
            for label, lib in order:
                print(f"round {k + 1}/{rounds}: {label}", flush=True)
                for key, value in run_work_precision(lib, os.path.join(tmp, f"{label}{k}")).items():
                    samples[label][key].append(value)
                if with_node:
                    for key, value in run_node_load(lib, os.path.join(tmp, f"{label}{k}")).items():
                        samples[label][key].append(value)
    ratios = defaultdict(list)
    spread = defaultdict(list)
    for key in sorted(set(samples["old"]) & set(samples["new"])):
        a, b = statistics.median(samples["old"][key]), statistics.median(samples["new"][key])
        if a > 0 and b > 0:
            group = (key[0], key[2] if key[0] != "node_load" else f"{key[1]}, {key[2]}, {key[3]}")
            ratios[group].append(b / a)
            # Between rounds of the same build: the noise floor of a ratio.
            for label in ("old", "new"):
                values = samples[label][key]
                if len(values) > 1 and min(values) > 0:
                    spread[group].append(max(values) / min(values))
    lines = [f"Before ({old}) against after ({new}): CPU of after / before, medians over {rounds} interleaved "
             "rounds (ABBA order); per group the median over its points and the range of those ratios; 'noise' is the median "
             "max/min of one build's own rounds.", "",
             "| benchmark | method or case | points | ratio after / before (median) | range | noise |",
             "|---|---|---|---|---|---|"]
    everything = []
    for group in sorted(ratios):
        r = ratios[group]
        everything += r
        noise = statistics.median(spread[group]) if spread[group] else float("nan")
        lines.append(f"| {group[0]} | {group[1]} | {len(r)} | {statistics.median(r):.3f} | {min(r):.2f} – "
                     f"{max(r):.2f} | {noise:.2f} |")
    lines += ["", f"All {len(everything)} points: median ratio {statistics.median(everything):.3f}."]
    with open(output, "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
