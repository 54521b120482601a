"""Plots of a top's state (spinning_top/TopState on ~state), live from the node or from a bag.

Debian bookworm has no rqt_plot: this is the package's plotting tool, on matplotlib.

    rosrun spinning_top plot                                  # live, the node's own top
    rosrun spinning_top plot --bag top.bag --output top.png   # a recording, to a PNG
    rosrun spinning_top plot --topic /spinning_top/slow/state --topic /spinning_top/fast/state \\
        --fields tilt,normal_force --path --duration 5 --output two.png

Any numeric field of the message is a series, nested ones with dots (``angular_velocity.z``).
``--path`` adds the tip's path on the floor (``contact_point.x`` against ``.y``). The time axis
is the message stamp (simulated time under use_sim_time).
"""

import argparse
import os
import sys
import time

DEFAULT_TOPIC = "/spinning_top/state"
DEFAULT_FIELDS = ("normal_force", "tilt", "energy")
# Units of the message's fields, for the axis labels (msg/TopState.msg).
UNITS = {
    "time": "s", "tilt": "rad", "heading": "rad", "spin_angle": "rad", "precession_rate": "rad/s",
    "nutation_rate": "rad/s", "spin": "rad/s", "angular_velocity": "rad/s", "center_of_mass": "m",
    "center_of_mass_velocity": "m/s", "contact_point": "m", "normal_force": "N", "contact_force": "N",
    "energy": "J", "dissipated_energy": "J", "energy_balance": "1", "quaternion_norm_error": "1",
    "constraint_residual": "m",
}


def field_value(message, field):
    """The number at a dotted field path of a message; ValueError if there is none."""
    value = message
    for part in field.split("."):
        if not hasattr(value, part):
            raise ValueError(f"{type(message).__name__} has no field '{field}'")
        value = getattr(value, part)
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f"field '{field}' is not a number (it is {type(value).__name__})")
    return float(value)


class Series:
    """The samples of one topic: stamps and the chosen fields (and the tip's path)."""

    def __init__(self, topic, fields, path):
        self.topic = topic
        self.fields = list(fields)
        self.path = path
        self.stamps = []
        self.values = {field: [] for field in self.fields}
        self.path_x, self.path_y = [], []

    def add(self, message):
        values = {field: field_value(message, field) for field in self.fields}  # all or nothing
        self.stamps.append(message.header.stamp.to_sec())
        for field, value in values.items():
            self.values[field].append(value)
        if self.path:
            self.path_x.append(message.contact_point.x)
            self.path_y.append(message.contact_point.y)

    def __len__(self):
        return len(self.stamps)


def read_bag(path, topics, fields, show_path):
    """Series of every topic from a bag (rosbag); ValueError if a topic holds no message."""
    import rosbag

    series = {topic: Series(topic, fields, show_path) for topic in topics}
    try:
        with rosbag.Bag(path) as bag:
            for topic, message, _ in bag.read_messages(topics=list(topics)):
                series[topic].add(message)
    except rosbag.ROSBagException as error:  # not a bag, or a damaged one
        raise ValueError(f"{path}: {error}") from None
    empty = [topic for topic, s in series.items() if len(s) == 0]
    if empty:
        raise ValueError(f"{path}: no message on {', '.join(empty)}")
    return [series[topic] for topic in topics]


def label(field):
    unit = UNITS.get(field.split(".")[0])
    return f"{field} [{unit}]" if unit else field


def draw(series, figure=None):
    """A figure with one panel per field (every topic a line) and the path panel."""
    import matplotlib.pyplot as plt

    fields = series[0].fields
    panels = len(fields) + (1 if series[0].path else 0)
    if figure is None:
        figure = plt.figure(figsize=(8, 2.4 * panels))
    figure.clear()
    axes = figure.subplots(panels, 1, squeeze=False)[:, 0]
    for axis, field in zip(axes, fields):
        for s in series:
            axis.plot(s.stamps, s.values[field], lw=0.9, label=s.topic)
        axis.set_ylabel(label(field))
        axis.set_xlabel("stamp [s]")
        axis.grid(alpha=0.3)
    if series[0].path:
        axis = axes[-1]
        for s in series:
            axis.plot(s.path_x, s.path_y, lw=0.7, label=s.topic)
        axis.set_xlabel("contact_point.x [m]")
        axis.set_ylabel("contact_point.y [m]")
        axis.set_aspect("equal", adjustable="datalim")
        axis.set_title("path of the tip on the floor", fontsize=9)
        axis.grid(alpha=0.3)
    if len(series) > 1:
        axes[0].legend(fontsize=8, loc="best")
    figure.tight_layout()
    return figure


def record_live(topics, fields, show_path, duration, live_figure):
    """Subscribes (rospy) and collects until `duration` wall seconds pass or Ctrl-C; redraws
    the figure about twice a second when there is a window."""
    import threading

    import rosgraph
    import rospy
    from spinning_top.msg import TopState

    if not rosgraph.is_master_online():  # rospy would wait for one forever
        raise ValueError(f"no ROS master at {rosgraph.get_master_uri()} (start the node, or give --bag)")
    rospy.init_node("spinning_top_plot", anonymous=True, disable_signals=True)
    series = [Series(topic, fields, show_path) for topic in topics]
    lock = threading.Lock()

    def keep(s):
        def callback(message):
            with lock:
                s.add(message)
        return callback

    subscribers = [rospy.Subscriber(s.topic, TopState, keep(s), queue_size=10000) for s in series]
    start = time.monotonic()
    try:
        while duration is None or time.monotonic() - start < duration:
            time.sleep(0.5)
            if live_figure is not None and all(len(s) > 1 for s in series):
                import matplotlib.pyplot as plt

                with lock:
                    draw(series, live_figure)
                plt.pause(0.01)
                if not plt.fignum_exists(live_figure.number):
                    break
    except KeyboardInterrupt:
        pass
    for subscriber in subscribers:
        subscriber.unregister()
    rospy.signal_shutdown("done")
    empty = [s.topic for s in series if len(s) == 0]
    if empty:
        raise ValueError(f"no message on {', '.join(empty)} (is the node running? rostopic list)")
    return series


def main(argv=None):
    parser = argparse.ArgumentParser(prog="rosrun spinning_top plot", description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter,
                                     epilog="\n\n".join(__doc__.split("\n\n")[1:]))
    parser.add_argument("--bag", help="read this bag instead of subscribing")
    parser.add_argument("--topic", action="append", help=f"TopState topic, repeatable (default {DEFAULT_TOPIC})")
    parser.add_argument("--fields", default=",".join(DEFAULT_FIELDS),
                        help="comma-separated fields, dots for nested ones (default %(default)s)")
    parser.add_argument("--path", action="store_true", help="add the tip's path on the floor")
    parser.add_argument("--duration", type=float, help="live: wall seconds to collect (default: until Ctrl-C "
                        "or the window closes)")
    parser.add_argument("--output", help="save the figure to this file (PNG, SVG, PDF by extension)")
    parser.add_argument("--no-show", action="store_true", help="do not open a window")
    args = parser.parse_args(argv)

    topics = args.topic or [DEFAULT_TOPIC]
    fields = [f.strip() for f in args.fields.split(",") if f.strip()]
    if not fields and not args.path:
        parser.error("nothing to plot: give --fields or --path")
    if args.duration is not None and not args.duration > 0:
        parser.error("--duration must be > 0 s")
    if args.bag is None and args.duration is None and args.no_show:
        parser.error("live with --no-show needs --duration")
    import matplotlib

    show = not args.no_show and bool(os.environ.get("DISPLAY"))
    if not show:
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    try:
        if args.bag:
            series = read_bag(args.bag, topics, fields, args.path)
        else:
            live_figure = plt.figure(figsize=(8, 2.4 * (len(fields) + args.path))) if show else None
            if live_figure is not None:
                plt.ion()
            series = record_live(topics, fields, args.path, args.duration, live_figure)
    except (ValueError, OSError) as error:
        print(f"plot: {error}", file=sys.stderr)
        return 1
    figure = draw(series)
    for s in series:
        print(f"plot: {s.topic}: {len(s)} messages, stamps {s.stamps[0]:.6f} to {s.stamps[-1]:.6f} s")
    if args.output:
        figure.savefig(args.output, dpi=110)
        print(f"plot: wrote {args.output}")
    if show:
        plt.ioff()
        plt.show()
    return 0


if __name__ == "__main__":
    sys.exit(main())
