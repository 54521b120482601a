"""Stability maps of a sweep (issue 11): each case's outcome, and when its event came, over two
varied keys; the sleeping-top threshold drawn where it applies. Cases whose tip left the floor
(issue 18: it flies, lands and goes on) are drawn apart: `hops` where the run went on to the
duration, `fallen after hops` where it fell; value="max_hop_height" or "lift_offs" maps the hops.

    from spinning_top import stability_map
    stability_map.plot(rows, "initial/spin", "initial/tilt", "map.png")
"""
import math
import os

import numpy as np

from spinning_top import _cli, _core

#: Outcome -> (colour, legend label), in legend order: the run's outcome column, with the hops
#: (lift_offs > 0) and a state refused at the release (end_time 0) told apart.
OUTCOMES = {
    "none": ("#4a9c3b", "stays up (no event)"),
    "hops": ("#f2b134", "hops (lifts off, lands, goes on to the end)"),
    "lift_off": ("#2f6db5", "lift-off ends the run (stop, or a pivot that cannot fly)"),
    "at_release": ("#9ecae1", "invalid at release (R < 0 or axis below the floor at t = 0)"),
    "fallen": ("#c8423a", "fallen (axis reaches the floor)"),
    "fallen_after_hops": ("#7b2a24", "fallen after hops"),
    "energy_drift": ("#8e44ad", "energy_drift (numerical)"),
    "non_finite": ("#000000", "non_finite (numerical)"),
    "out_of_steps": ("#999999", "out of steps"),
    "refused": ("#dddddd", "refused by the core"),
}


def _value(base, key):
    """A key's value in the sweep's base keys, or its documented default."""
    if key in base:
        return float(base[key])
    for spec in _core.parameter_specs():
        if spec["key"] == key:
            return float(spec["default"])
    raise KeyError(key)


def sleeping_threshold(base):
    """omega_crit [rad/s] above which the upright (sleeping) top is stable: C^2 wZ^2 > 4 A' m g h,
    A' = A0 = A + m h^2 on the pivot, A on the frictionless floor (doc/spec/PHYSICS.md,
    "Sleeping top"). None for the viscous scene, where friction changes the answer."""
    scene = str(base.get("scene", "fixed_tip"))
    m, a, c = _value(base, "mass"), _value(base, "inertia_transverse"), _value(base, "inertia_axial")
    h, g = _value(base, "tip_distance"), _value(base, "gravity")
    if scene == "fixed_tip":
        transverse = a + m * h * h
    elif scene == "frictionless":
        transverse = a
    else:
        return None
    return 2.0 * math.sqrt(transverse * m * g * h) / c


def _is_grid(rows, x, y):
    return rows[x].nunique() * rows[y].nunique() == len(rows)


def _grid(rows, x, y, values):
    xs, ys = np.unique(rows[x]), np.unique(rows[y])
    image = np.full((len(ys), len(xs)), np.nan)
    image[np.searchsorted(ys, rows[y]), np.searchsorted(xs, rows[x])] = values
    return xs, ys, image


def _edges(centres):
    if len(centres) == 1:
        return np.array([centres[0] - 0.5, centres[0] + 0.5])
    middle = 0.5 * (centres[1:] + centres[:-1])
    return np.concatenate([[2 * centres[0] - middle[0]], middle, [2 * centres[-1] - middle[-1]]])


#: Columns that count or measure the hops: 0 means the tip never left the floor, shown as "none".
HOP_COLUMNS = ("lift_offs", "landings", "max_hop_height")


def shown_outcomes(rows):
    """Each case's entry of OUTCOMES: its outcome, with the hops and the refusals at release apart."""
    outcome = rows["outcome"].to_numpy(dtype=object)
    hopped = rows["lift_offs"].to_numpy(dtype=float) > 0 if "lift_offs" in rows else np.zeros(len(rows), bool)
    # A state the model refuses from the start (the floor would have to pull the tip at release)
    # is told apart from a lift-off that the motion reaches.
    at_release = (rows["end_time"].to_numpy(dtype=float) == 0.0) & np.isin(outcome, ["lift_off", "fallen"])
    shown = np.where(at_release, "at_release", outcome)
    shown = np.where(hopped & (outcome == "none"), "hops", shown)
    return np.where(hopped & (outcome == "fallen"), "fallen_after_hops", shown)


def plot(rows, x, y, path, title=None, value="event_time", base=None, duration=None):
    """Writes a picture of two panels over (x, y) to exactly `path`, as PNG, SVG, PDF, ... by its
    extension (another extension, a directory, a missing directory or a failed write raise
    ValueError; no file is left half written): the outcome of each case, and `value`, a numeric
    column of the rows (default the time of its event; cases without a value in grey; e.g.
    final_tilt shows how friction raises or lowers the axis, max_hop_height or lift_offs the hops,
    grey where the tip never left the floor). A grid design is drawn as cells, a
    random or Sobol one as points. Where x or y is initial/spin and the other keys of the threshold are fixed, the
    sleeping-top threshold +-omega_crit is drawn as a line on both panels.

    base and duration: the sweep's base keys and duration (for the threshold and the title); by
    default those sweep.run kept with the rows (pandas >= 1.0 keeps them; with pandas 0.25, as
    Ubuntu 20.04 has, or rows read back from a file, pass them, else no threshold is drawn)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Patch

    fmt = None
    if isinstance(path, (str, os.PathLike)):  # else a file object: PNG
        fmt = _cli.check_output(None, path, _cli.figure_formats())
    for key in (x, y):
        if key not in rows:
            raise ValueError(f"{key} is not a varied key of this sweep (columns: {', '.join(rows.columns)})")
    from spinning_top.sweep import sweep_info

    kept_base, kept_duration = sweep_info(rows)
    known_base = base is not None or kept_base is not None
    base = dict(base if base is not None else kept_base or {})
    duration = duration if duration is not None else kept_duration
    names = list(OUTCOMES)
    shown = shown_outcomes(rows)
    codes = np.array([names.index(o) if o in OUTCOMES else names.index("refused") for o in shown], float)
    if value not in rows or rows[value].dtype.kind not in "fiub":
        raise ValueError(f"--value {value}: not a numeric column of the rows")
    shade = rows[value].to_numpy(dtype=float)
    if value in HOP_COLUMNS:
        shade = np.where(shade > 0, shade, np.nan)  # grey: the tip never left the floor

    fig, (left, right) = plt.subplots(1, 2, figsize=(13, 5.2), constrained_layout=True)
    outcome_map = ListedColormap([OUTCOMES[n][0] for n in names])
    grid = _is_grid(rows, x, y)
    if grid:
        xs, ys, image = _grid(rows, x, y, codes)
        left.pcolormesh(_edges(xs), _edges(ys), image, cmap=outcome_map, vmin=-0.5, vmax=len(names) - 0.5)
        xs, ys, shades = _grid(rows, x, y, shade)
        right.pcolormesh(_edges(xs), _edges(ys), np.where(np.isnan(shades), 0.0, np.nan), cmap=ListedColormap(["#d9d9d9"]))
        mesh = right.pcolormesh(_edges(xs), _edges(ys), shades, cmap="viridis")
    else:
        size = max(2.0, min(30.0, 20000.0 / len(rows)))
        left.scatter(rows[x], rows[y], c=codes, cmap=outcome_map, vmin=-0.5, vmax=len(names) - 0.5, s=size, lw=0)
        none = np.isnan(shade)
        right.scatter(rows[x][none], rows[y][none], c="#d9d9d9", s=size, lw=0)
        mesh = right.scatter(rows[x][~none], rows[y][~none], c=shade[~none], cmap="viridis", s=size, lw=0)
    if value == "event_time":
        label = "event time [s]" + (f" (grey: none within {duration:g} s)" if duration else "")
    elif value in HOP_COLUMNS:
        label = _label(value) + (" (grey: never left the floor)" if np.isnan(shade).any() else "")
    else:
        label = _label(value) + (" (grey: none)" if np.isnan(shade).any() else "")
    fig.colorbar(mesh, ax=right, label=label)
    present = [n for n in names if (shown == n).any()]
    handles = [Patch(color=OUTCOMES[n][0], label=OUTCOMES[n][1]) for n in present]

    threshold = None
    threshold_keys = {"mass", "inertia_transverse", "inertia_axial", "tip_distance", "gravity", "scene"}
    if known_base and "initial/spin" in (x, y) and not threshold_keys & set(rows.columns):
        threshold = sleeping_threshold(base)
    if threshold is not None:
        label = "ω_crit = 2√(A₀ m g h)/C" if str(base.get("scene", "fixed_tip")) == "fixed_tip" else "ω_crit = 2√(A m g h)/C"
        for ax in (left, right):
            low, high = rows["initial/spin"].min(), rows["initial/spin"].max()
            for w in (threshold, -threshold):
                if low <= w <= high:
                    line = ax.axvline if x == "initial/spin" else ax.axhline
                    line(w, color="white", lw=2.2)
                    line(w, color="black", lw=1.0, ls="--")
        handles.append(plt.Line2D([], [], color="black", ls="--", label=f"{label} = {threshold:.4g} rad/s"))
    left.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, -0.13), ncol=2, fontsize=8, frameon=False)
    for ax, what in ((left, "outcome"), (right, "time of the first event" if value == "event_time" else value)):
        ax.set_xlabel(_label(x))
        ax.set_ylabel(_label(y))
        ax.set_title(what)
    scene = base.get("scene", "")
    fig.suptitle(title or f"{scene} top: {len(rows)} cases of {duration:g} s" if duration else title or scene)
    try:
        if fmt is None:
            fig.savefig(path, dpi=110, format="png")
        else:  # rendered in memory, then written whole to exactly `path` (never `path`.png)
            _cli.write_file(None, path, _cli.figure_bytes(fig, fmt, dpi=110))
    finally:
        plt.close(fig)


def _label(key):
    """A configuration key or an outcome column with its unit, e.g. "initial/spin [rad/s]"."""
    from spinning_top.sweep import OUTCOME_COLUMNS  # its descriptions start with the unit

    for spec in _core.parameter_specs():
        if spec["key"] == key:
            return f"{key} [{spec['unit']}]" if spec["unit"] else key
    description = OUTCOME_COLUMNS.get(key, "")
    return f"{key} {description.split(']')[0]}]" if description.startswith("[") else key
