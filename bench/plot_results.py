#!/usr/bin/env python3
"""Plots and summary of the work-precision benchmark (doc/benchmark.md).

Reads DIR/work_precision.csv, DIR/long_run_energy.csv, DIR/reference_check.csv and (if present)
DIR/dense_sampling.csv and DIR/default_ratio.md written by the work_precision executable, and
DIR/reinit_cost.md written by reinit_cost; a method with a single point (exact: no step, no
tolerance) is drawn as one marker and its CPU time at a larger target error is that point's ('≤');
writes DIR/work_precision_<scene>.png, DIR/long_run_energy.png, DIR/dense_sampling.png and
DIR/summary.md, and prints the ratio table. Usage: plot_results.py [DIR]
"""
import csv
import math
import os
import sys
from collections import OrderedDict, defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

TARGETS = [1e-6, 1e-9]  # max attitude error [rad] at which the methods' CPU times are compared
AMBITION_RKF78 = 1e-6   # DEVELOPERS.md: 10x less CPU than odeint's RKF78 at 1e-6 rad


def read_rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def curves(rows):
    """{scene: {(family, method): [(param, cpu, attitude, energy, normal, steps)...]}} in sweep order."""
    out = defaultdict(OrderedDict)
    for r in rows:
        key = (r["family"], r["method"])
        out[r["scene"]].setdefault(key, []).append(
            (float(r["parameter"]), float(r["cpu_seconds"]), float(r["max_attitude_error_rad"]),
             float(r["max_energy_error_rel_mgh"]), float(r["max_normal_force_error_rel_mg"]), int(r["steps"])))
    return out


def cpu_at_error(points, target):
    """CPU time [s] at which a method reaches `target` attitude error, by linear interpolation
    of log(cpu) against log(error) between consecutive sweep points that bracket the target
    (the cheapest if several do). Returns (cpu, exact): exact False means an upper bound (the
    method's cheapest point is already below the target), None if the target is never reached."""
    best = None
    for (_, c0, e0, *_), (_, c1, e1, *_) in zip(points, points[1:]):
        if min(e0, e1) <= target <= max(e0, e1) and e0 > 0 and e1 > 0 and e0 != e1:
            w = (math.log(target) - math.log(e0)) / (math.log(e1) - math.log(e0))
            c = math.exp(math.log(c0) + w * (math.log(c1) - math.log(c0)))
            best = c if best is None else min(best, c)
    if best is not None:
        return best, True
    below = [p for p in points if p[2] <= target]
    if below:
        return min(p[1] for p in below), False
    return None, True


def fmt_ms(value):
    cpu, exact = value
    if cpu is None:
        return "not reached in the sweep"
    return ("" if exact else "≤ ") + f"{cpu * 1e3:.3g}"


def dense_plot(directory, rows):
    """Whole-attitude error against CPU time at a state every 1 ms, one panel per scene: the default
    (fresh and after reset()), our other methods, and odeint's (a peer's tolerance sweep as a line)."""
    scenes = list(OrderedDict.fromkeys(r["scene"] for r in rows))
    fig, axes = plt.subplots(1, len(scenes), figsize=(5 * len(scenes), 4.5), squeeze=False)
    for ax, scene in zip(axes[0], scenes):
        series = OrderedDict()
        for r in rows:
            if r["scene"] == scene:
                series.setdefault((r["family"], r["method"]), []).append(r)
        for (family, method), points in series.items():
            errors = [max(float(p["max_attitude_error_rad"] or p["max_axis_error_rad"]), 1e-16) for p in points]
            if family == "default":
                p = points[0]
                if p.get("cpu_fresh_seconds"):
                    ax.loglog([float(p["cpu_fresh_seconds"]) * 1e3], errors, "r*", markersize=14,
                              label=f"{method}, fresh")
                ax.loglog([float(p["cpu_seconds"]) * 1e3], errors, "r*", markersize=10, markerfacecolor="none",
                          label=f"{method}, after reset()")
                continue
            cpu = [float(p["cpu_seconds"]) * 1e3 for p in points]
            style = dict(linestyle="-" if len(points) > 1 else "none", marker="o" if family == "ours" else "s",
                         markersize=4)
            if family == "odeint":
                style["linestyle"] = "--" if len(points) > 1 else "none"
            ax.loglog(cpu, errors, label=(method if family == "ours" else "odeint " + method), **style)
        ax.set_title(scene)
        ax.set_xlabel("CPU ms for 10000 requests (10 s at 1 kHz)")
        ax.set_ylabel("max whole-attitude error [rad]")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=6)
    fig.suptitle("The default at the node's sampling (a state every 1 ms) against the peers")
    fig.tight_layout()
    fig.savefig(os.path.join(directory, "dense_sampling.png"), dpi=90)
    plt.close(fig)


def main():
    directory = sys.argv[1] if len(sys.argv) > 1 else "."
    rows = read_rows(os.path.join(directory, "work_precision.csv"))
    data = curves(rows)
    checks = read_rows(os.path.join(directory, "reference_check.csv"))

    # ---- plots: error vs CPU, one figure per scene ----
    for scene, methods in data.items():
        fig, axes = plt.subplots(1, 3, figsize=(16, 5))
        ours = [k for k in methods if k[0] == "ours"]
        cmap = plt.get_cmap("tab10")
        colors = {k: cmap(i % 10) for i, k in enumerate(ours)}
        peer_colors = {"runge_kutta4": "0.55", "runge_kutta_dopri5": "tab:olive",
                       "runge_kutta_fehlberg78": "black", "rosenbrock4": "tab:cyan"}
        for key, points in methods.items():
            family, method = key
            cpu = [p[1] * 1e3 for p in points]
            style = dict(linestyle="-" if family == "ours" else "--", marker="o" if family == "ours" else "s",
                         markersize=4, color=colors.get(key, peer_colors.get(method, "gray")),
                         label=(method if family == "ours" else "odeint " + method))
            for ax, column in zip(axes, (2, 3, 4)):
                ax.loglog(cpu, [max(p[column], 1e-16) for p in points], **style)
        titles = ("max attitude error [rad]", "max energy error / (m g h)" +
                  (" (E + W - E0)" if scene.startswith("viscous") else ""), "max |R - R_ref| / (m g)")
        for ax, title in zip(axes, titles):
            ax.set_xlabel("CPU time per 10 s simulated [ms]")
            ax.set_ylabel(title)
            ax.grid(True, which="both", alpha=0.3)
        axes[0].legend(fontsize=7)
        fig.suptitle(f"Work-precision, scene {scene} (toy top; ours solid, Boost.Odeint dashed)")
        fig.tight_layout()
        fig.savefig(os.path.join(directory, f"work_precision_{scene}.png"), dpi=90)
        plt.close(fig)

    # ---- long runs ----
    long_path = os.path.join(directory, "long_run_energy.csv")
    long_rows = read_rows(long_path) if os.path.exists(long_path) else []
    long_data = defaultdict(OrderedDict)
    for r in long_rows:
        long_data[r["scene"]].setdefault((r["family"], r["method"], r["setting"]), []).append(
            (float(r["time"]), float(r["energy_error_rel_mgh"])))
    if long_data:
        fig, axes = plt.subplots(1, len(long_data), figsize=(6 * len(long_data), 5), squeeze=False)
        for ax, (scene, series) in zip(axes[0], long_data.items()):
            for (family, method, setting), pts in series.items():
                ax.loglog([p[0] for p in pts], [max(abs(p[1]), 1e-17) for p in pts],
                          linestyle="-" if family == "ours" else "--",
                          label=(method if family == "ours" else "odeint " + method) + f" ({setting})")
            ax.set_title(scene)
            ax.set_xlabel("simulated time [s]")
            ax.set_ylabel("|E - E0| / (m g h)" + (" with E + W" if scene.startswith("viscous") else ""))
            ax.grid(True, which="both", alpha=0.3)
            ax.legend(fontsize=6)
        fig.suptitle("Energy error of long runs (step 1e-3 s or tolerance 1e-10)")
        fig.tight_layout()
        fig.savefig(os.path.join(directory, "long_run_energy.png"), dpi=90)
        plt.close(fig)

    # ---- ratio table ----
    lines = []
    lines.append("| scene | target error [rad] | best of ours (CPU ms) | best odeint peer (CPU ms) | ours / best peer | ours / RKF78 |")
    lines.append("|---|---|---|---|---|---|")
    per_method = []
    for scene, methods in data.items():
        for target in TARGETS:
            ours = {m: cpu_at_error(p, target) for (f, m), p in methods.items() if f == "ours"}
            peers = {m: cpu_at_error(p, target) for (f, m), p in methods.items() if f == "odeint"}
            for f, table in (("ours", ours), ("odeint", peers)):
                for m, v in table.items():
                    per_method.append((scene, target, f, m, v))

            def best(table):
                found = [(v[0], m, v[1]) for m, v in table.items() if v[0] is not None]
                return min(found) if found else None

            bo, bp = best(ours), best(peers)
            rkf = peers.get("runge_kutta_fehlberg78", (None, True))
            ratio = f"{bo[0] / bp[0]:.2f}" if bo and bp else "n/a"
            if bo and bp and not (bo[2] and bp[2]):
                ratio += " (bound)"
            ratio_rkf = f"{bo[0] / rkf[0]:.2f}" if bo and rkf[0] else "n/a"
            if bo and rkf[0] and not (bo[2] and rkf[1]):
                ratio_rkf += " (bound)"
            lines.append(f"| {scene} | {target:g} | {bo[1] + ' ' + fmt_ms((bo[0], bo[2])) if bo else 'not reached in the sweep'} | "
                         f"{bp[1] + ' ' + fmt_ms((bp[0], bp[2])) if bp else 'not reached in the sweep'} | {ratio} | {ratio_rkf} |")
    ratio_table = "\n".join(lines)
    print("\nCPU time at equal max attitude error (interpolated in log-log; '≤' = the cheapest run is already below the target):")
    print(ratio_table)

    method_lines = ["| scene | target [rad] | family | method | CPU ms |", "|---|---|---|---|---|"]
    for scene, target, f, m, v in per_method:
        method_lines.append(f"| {scene} | {target:g} | {f} | {m} | {fmt_ms(v)} |")

    ambition = []
    if "fixed_tip" in data:
        rkf = cpu_at_error(data["fixed_tip"].get(("odeint", "runge_kutta_fehlberg78"), []), AMBITION_RKF78)
        found = [(cpu_at_error(p, AMBITION_RKF78), m) for (f, m), p in data["fixed_tip"].items() if f == "ours"]
        found = [(v[0], m) for v, m in found if v[0] is not None]
        if rkf[0] and found:
            cpu, m = min(found)
            points = data["fixed_tip"][("ours", m)]
            reached = min(p[2] for p in points if p[1] <= cpu * (1 + 1e-12))
            note = (f" (its cheapest run already reaches {reached:.2g} rad)"
                    if not cpu_at_error(points, AMBITION_RKF78)[1] else "")
            ambition.append(f"- Fixed tip at 1e-6 rad: odeint RKF78 needs {rkf[0] * 1e3:.3g} ms CPU per 10 s simulated "
                            f"(DEVELOPERS.md assumed 0.6 ms); our best, {m}, needs {cpu * 1e3:.3g} ms{note}: "
                            f"{rkf[0] / cpu:.2f}x less CPU than RKF78 (the ambition is 10x).")
    for line in ambition:
        print(line)

    dense_lines = []
    dense_path = os.path.join(directory, "dense_sampling.csv")
    dense_rows = read_rows(dense_path) if os.path.exists(dense_path) else []
    for r in dense_rows:
        if "max_axis_error_rad" not in r:  # an older file: its attitude error was the axis angle
            r["max_axis_error_rad"], r["max_attitude_error_rad"] = r["max_attitude_error_rad"], ""
    if dense_rows:
        def cell(r, key, scale=1.0, fmt=".3g"):
            value = r.get(key) or ""  # columns an older dense_sampling.csv lacks are left blank
            return format(float(value) * scale, fmt) if value else ""
        dense_lines = ["Every series at a state every 1 ms over 10 s (10000 requests, output off): CPU ms after "
                       "`reset()` (odeint: its stepper built in the timed run), from a fresh simulator for the "
                       "default, steps, and the max errors on that grid: the whole attitude (rotation angle), the "
                       "axis, |R - R_ref| / (m g).", "",
                       "| scene | family | method | setting | CPU ms | fresh CPU ms | steps | attitude [rad] | "
                       "axis [rad] | R [m g] |",
                       "|---|---|---|---|---|---|---|---|---|---|"]
        for r in dense_rows:
            dense_lines.append(f"| {r['scene']} | {r['family']} | {r['method']} | {r['setting']} | "
                               f"{cell(r, 'cpu_seconds', 1e3)} | {cell(r, 'cpu_fresh_seconds', 1e3)} | "
                               f"{r.get('steps', '')} | {cell(r, 'max_attitude_error_rad', fmt='.2g')} | "
                               f"{cell(r, 'max_axis_error_rad', fmt='.2g')} | "
                               f"{cell(r, 'max_normal_force_error_rel_mg', fmt='.2g')} |")
        dense_plot(directory, dense_rows)

    def text_of(name):
        path = os.path.join(directory, name)
        return open(path).read().strip() if os.path.exists(path) else ""

    default_ratio, reinit_cost = text_of("default_ratio.md"), text_of("reinit_cost.md")

    check_lines = ["| scene | quantity | value |", "|---|---|---|"]
    for c in checks:
        check_lines.append(f"| {c['scene']} | {c['what']} | {c['value']} |")

    with open(os.path.join(directory, "summary.md"), "w") as f:
        f.write("<!-- generated by scripts/bench.sh (bench/plot_results.py); do not edit -->\n")
        f.write("### Work-precision: CPU time at equal accuracy\n\n")
        f.write("CPU time per 10 s simulated (median of repeats, output off) at which each family first reaches the "
                "target max attitude error, interpolated in log-log between measured points; the ratio is ours / best "
                "odeint peer (below 1: ours is cheaper). '≤' and '(bound)': the method's cheapest measured run is "
                "already below the target, so its CPU time there is an upper bound. A sweep stops at 1.5 s CPU per "
                "run ('not reached in the sweep').\n\n")
        f.write(ratio_table + "\n\n")
        if ambition:
            f.write("\n".join(ambition) + "\n\n")
        f.write("![fixed tip](work_precision_fixed_tip.png)\n\n")
        for scene in data:
            if scene != "fixed_tip":
                f.write(f"![{scene}](work_precision_{scene}.png)\n\n")
        if long_data:
            f.write("![long runs](long_run_energy.png)\n\n")
        f.write("<details><summary>Per-method CPU time at the targets</summary>\n\n" + "\n".join(method_lines) +
                "\n\n</details>\n\n")
        if default_ratio or dense_lines:
            f.write("### The default at the node's 1 ms sampling\n\n")
            if default_ratio:
                f.write(default_ratio + "\n\n")
            if dense_lines:
                f.write("![dense sampling](dense_sampling.png)\n\n")
                f.write("<details><summary>Every series at 1 ms</summary>\n\n" + "\n".join(dense_lines) +
                        "\n\n</details>\n\n")
        if reinit_cost:
            f.write("### Re-initialisation of the default\n\n" + reinit_cost + "\n\n")
        f.write("### References and their checks\n\n" + "\n".join(check_lines) + "\n")


if __name__ == "__main__":
    main()
