"""Sweep throughput (issue 11): cases of 10 s per second per core for each scene at the default
settings, a 1e6-case stability map on every local core, and the overhead of a Dask cluster per
case. Writes bench/results/sweep.md (spliced into the README by update_readme.py).

    source build/devel/setup.bash && /usr/bin/python3 bench/sweep_throughput.py bench/results [--quick]

CPU per case is the process's CPU time over a batch run on this thread (one core); the map and
the cluster are timed by the wall clock (they use every core). Nothing here is asserted: the
tests check the rows, this measures their cost.
"""
import os
import pathlib
import platform
import sys
import time

import numpy as np

import spinning_top as st
from spinning_top import _core, sweep

QUICK = "--quick" in sys.argv
OUTPUT = pathlib.Path(next((a for a in sys.argv[1:] if not a.startswith("--")), "bench/results"))
SOURCE = pathlib.Path(__file__).resolve().parents[1]

#: The README map's design: spin 0-200 rad/s x tilt 0-0.85 rad, released without precession. The
#: shipped scenes' rim (rim_radius, rim_distance) touches the floor at 0.857 rad: a larger tilt
#: is refused, and a refusal would count as a (free) case.
MAP_RANGES = {"initial/spin": (0.0, 200.0), "initial/tilt": (0.0, 0.85)}
#: Tops that all run the whole 10 s (no event ends them early): the cost of a full case.
FULL_RANGES = {"initial/spin": (100.0, 200.0), "initial/tilt": (0.1, 0.8)}


def per_core(base, ranges, cases, repeats=3):
    """Cases per CPU second on one thread (the best of `repeats`), and the rows' outcome mix."""
    design = sweep.design(ranges, "random", cases, seed=11)
    columns = {k: np.ascontiguousarray(v) for k, v in design.items()}
    best, rows = float("inf"), None
    for _ in range(repeats):
        start = time.process_time()
        rows = _core.run_cases(base, columns, _core.CaseSettings(10.0))
        best = min(best, time.process_time() - start)
    outcomes = {}
    for o in rows["outcome"]:
        outcomes[o] = outcomes.get(o, 0) + 1
    methods = sorted(set(rows["method"]))
    return cases / best, best / cases, outcomes, methods


def main():
    lines = []

    def say(text=""):
        print(text, flush=True)
        lines.append(text)

    cores = len(os.sched_getaffinity(0)) or 1
    say(f"Measured by `bench/sweep_throughput.py`{' --quick' if QUICK else ''} on {cores} cores "
        f"({platform.processor() or platform.machine()}), Release build, default settings (`integrator: auto`, "
        "duration 10 s; a fixed step sampled at 1 kHz, exact and the interpolating methods with their own extremes). "
        "Cases are random tops of each range (seed 11).")
    say()
    say("| scene | cases | what runs | tops | cases of 10 s per s per core | CPU per case | outcomes |")
    say("|---|---|---|---|---|---|---|")
    scenes = [("fixed_tip", {}, 20000 if not QUICK else 4000), ("frictionless", {}, 20000 if not QUICK else 4000),
              ("viscous", {}, 400 if not QUICK else 100)]
    for scene, extra, cases in scenes:
        base = {**st.load_scene(SOURCE / "config" / f"{scene}.yaml"), **extra, "initial/precession_rate": 0.0}
        for label, ranges in (("map (spin 0-200, tilt 0-0.85)", MAP_RANGES), ("all upright 10 s (spin 100-200, tilt 0.1-0.8)", FULL_RANGES)):
            rate, cpu, outcomes, methods = per_core(base, ranges, cases, repeats=1 if scene == "viscous" else 3)
            mix = ", ".join(f"{n} {k}" for k, n in sorted(outcomes.items()))
            say(f"| {scene} | {cases} | {', '.join(methods)} | {label} | {rate:,.0f} | {cpu * 1e6:,.1f} us | {mix} |")
    say()

    # A 1e6-case map on every local core (threads; the core runs without the GIL).
    side = 1000 if not QUICK else 300
    base = {**st.load_scene(SOURCE / "config" / "fixed_tip.yaml"), "initial/precession_rate": 0.0}
    design = sweep.design({"initial/spin": (0.0, 200.0, side), "initial/tilt": (0.0, 0.85, side)})
    start, cpu0 = time.perf_counter(), time.process_time()
    rows = sweep.run(base, design)
    wall, cpu = time.perf_counter() - start, time.process_time() - cpu0
    say(f"A {side} x {side} = {side * side:,} case fixed-tip map (spin x tilt, 10 s each) on {cores} local cores: "
        f"{wall:.1f} s wall, {cpu:.1f} s CPU ({side * side / wall:,.0f} cases/s); "
        f"{(rows['outcome'] == 'fallen').sum():,} fall, {(rows['outcome'] == 'none').sum():,} stay up.")
    say()

    # Dask: a LocalCluster of one single-threaded worker process per core, the same sweep.
    from distributed import Client, LocalCluster

    n = 200000 if not QUICK else 40000
    design = sweep.design(MAP_RANGES, "random", n, seed=5)
    start = time.perf_counter()
    local = sweep.run(base, design)
    local_wall = time.perf_counter() - start
    start = time.perf_counter()
    with LocalCluster(n_workers=cores, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, \
            Client(cluster) as client:
        up = time.perf_counter() - start
        sweep.run(base, design, scheduler=client)  # workers import the module once
        start = time.perf_counter()
        remote = sweep.run(base, design, scheduler=client)
        remote_wall = time.perf_counter() - start
        tasks = len(sweep._batches(n, cores, None))
        # The cost of a task itself: many batches of one case each.
        few = {k: v[:2000] for k, v in design.items()}
        start = time.perf_counter()
        sweep.run(base, few, scheduler=client, batch_size=1)
        per_task = (time.perf_counter() - start) / 2000
    same = local.equals(remote)
    say(f"Dask `LocalCluster` ({cores} worker processes, 1 thread each; start-up {up:.1f} s, not counted): "
        f"{n:,} fixed-tip cases in {tasks} tasks took {remote_wall:.2f} s against {local_wall:.2f} s on local "
        f"threads: overhead {(remote_wall - local_wall) / n * 1e6:+.2f} us per case. With one case per task "
        f"a case costs {per_task * 1e3:.2f} ms of wall time: the batching (default: 16 tasks per worker, at most "
        f"{sweep.MAX_BATCH} cases) is what keeps the scheduler's cost small. Rows equal bit for bit: {same}.")
    OUTPUT.mkdir(parents=True, exist_ok=True)
    (OUTPUT / "sweep.md").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
