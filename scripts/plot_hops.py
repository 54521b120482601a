#!/usr/bin/env python3
"""The README's hop plot (issue 18, doc/spec/HYBRID.md): a top on the frictionless floor that lifts
off, flies, lands plastically and lifts off again; its tip's height and the floor's normal force
over 0.3 s, from the C++ core through the Python module (Simulator.run: the rows at the times asked
for and one at each transition).

    source build/devel/setup.bash      # or the build's devel space on PYTHONPATH
    /usr/bin/python3 scripts/plot_hops.py [--output doc/hops.png]
"""
import argparse
import pathlib
import sys

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
try:
    import spinning_top as st
except ImportError:  # not sourced: the build's devel space of this checkout
    sys.path[:0] = [str(ROOT / "build/devel/lib/python3/dist-packages"), str(ROOT / "python")]
    import spinning_top as st

#: The issue's hopping top: the toy top (config/frictionless.yaml) tilted 0.8 rad, precessing at
#: 60 rad/s about the vertical, spinning at 150 rad/s. R reaches 0 at 9.4 ms.
KEYS = {**st.load_scene(ROOT / "config" / "frictionless.yaml"), "initial/tilt": 0.8, "initial/precession_rate": 60.0}
DURATION = 0.3  # [s]
RATE = 1e4      # [Hz] rows; the transitions add their own


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--output", default=str(ROOT / "doc" / "hops.png"), help="PNG to write (default doc/hops.png)")
    args = parser.parse_args(argv)

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    run = st.Simulator(KEYS).run(np.arange(int(round(DURATION * RATE)) + 1) / RATE)
    row = st.run_case(KEYS, duration=DURATION)
    ms, mm = 1e3 * run["time"], 1e3 * run["tip_height"]
    weight = float(KEYS["mass"]) * float(KEYS["gravity"])
    lift_offs, landings = run["events"] == "lift_off", run["events"] == "landing"

    fig, (top, bottom) = plt.subplots(2, 1, figsize=(8, 4.6), sharex=True, height_ratios=[2, 1],
                                      constrained_layout=True)
    flying = run["phase"] == "flight"
    for ax in (top, bottom):
        ax.fill_between(ms, 0, 1, where=flying, transform=ax.get_xaxis_transform(), color="#f2b134", alpha=0.18,
                        lw=0, label="flight" if ax is top else None)
    top.plot(ms, mm, color="#2f6db5", lw=1.3, label="tip height $z_P$")
    top.plot(ms[lift_offs], mm[lift_offs], "^", color="#4a9c3b", ms=7, label="lift_off (R = 0)")
    top.plot(ms[landings], mm[landings], "v", color="#c8423a", ms=7, label="landing (plastic impulse)")
    top.axhline(1e3 * row["max_hop_height"], color="grey", lw=0.8, ls="--",
                label=f"max_hop_height {1e3 * row['max_hop_height']:.2f} mm")
    top.set_ylabel("tip height [mm]")
    top.set_ylim(-0.4, 1e3 * row["max_hop_height"] * 1.45)  # room for the legend above the highest hop
    top.legend(loc="upper right", fontsize=8, ncol=3, frameon=False)
    bottom.plot(ms, run["normal_force"] / weight, color="#555555", lw=1.0)
    bottom.plot(ms[lift_offs], np.zeros(lift_offs.sum()), "^", color="#4a9c3b", ms=6)
    bottom.set_ylabel("R / m g")
    bottom.set_xlabel("time [ms]")
    bottom.set_xlim(0, 1e3 * DURATION)
    fig.suptitle(f"frictionless top, tilt 0.8 rad, precession 60 rad/s, spin 150 rad/s: {int(row['lift_offs'])} "
                 f"lift-offs, {int(row['landings'])} landings in {DURATION:g} s", fontsize=10)
    fig.savefig(args.output, dpi=100)
    plt.close(fig)
    print(f"{args.output}: {int(row['lift_offs'])} lift-offs (first at {1e3 * row['first_lift_off_time']:.2f} ms), "
          f"{int(row['landings'])} landings, highest hop {1e3 * row['max_hop_height']:.3f} mm, "
          f"{1e3 * row['friction_work']:.1f} mJ lost in the landings")
    return 0


if __name__ == "__main__":
    sys.exit(main())
