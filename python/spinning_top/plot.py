"""Plots of a top's state (spinning_top/TopState on ~state), live from the node or from a bag.

Debian bookworm has no rqt_plot: this is the package's plotting tool, on matplotlib.

    rosrun spinning_top plot                                  # live, the node's own top
    rosrun spinning_top plot --bag top.bag --output top.png   # a recording, to a PNG
    rosrun spinning_top plot --topic /spinning_top/slow/state --topic /spinning_top/fast/state \\
        --fields tilt,normal_force --path --duration 5 --output two.png

Any numeric field of the message is a series, nested ones with dots (``angular_velocity.z``).
``--path`` adds the tip's path on the floor (``contact_point.x`` against ``.y``). The time axis
is the message stamp (simulated time under use_sim_time). Values that are not finite (nan, inf),
or lie beyond +-1e300 (where an axis cannot be scaled), are not drawn: a warning and the panel's
label count them.

``--output`` is written exactly as named, in the format of its extension (.png, .svg, .pdf, ...),
or refused before anything is read. Errors are one line naming the option, exit status 2.
"""

import argparse
import math
import os
import stat
import sys
import time

from spinning_top import _cli

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


#: The message fields' types that are numbers (genpy's primitive types).
NUMERIC_TYPES = {"float64", "float32", "int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64",
                 "byte", "char"}


def check_field(message_class, field):
    """Refuses (ValueError, `--fields FIELD: ...`) a field path that is not a numeric field of the
    message: each dotted part must be one of the message's declared fields (``__slots__``; no
    Python attribute such as ``imag`` or ``__class__``), the last a number."""
    option = f"--fields {_cli.short(field, quote=False)}"
    value, name = message_class(), message_class.__name__
    parts = field.split(".")
    for i, part in enumerate(parts):
        slots = getattr(value, "__slots__", ())
        if part not in slots:
            raise _cli.UsageError(option, f"{name} has no field {_cli.short(part, quote=False)}")
        kind = value._slot_types[slots.index(part)]
        path = ".".join(parts[:i + 1])
        if i + 1 < len(parts) and "/" not in kind:  # a number, text or time has no fields
            raise _cli.UsageError(option, f"{path} is a {kind}, it has no field "
                                  f"{_cli.short(parts[i + 1], quote=False)}")
        value, name = getattr(value, part), path
    if kind in NUMERIC_TYPES:
        return
    if "/" in kind and not kind.endswith("]"):
        raise _cli.UsageError(option, f"a {kind}, not a number; give one of its fields "
                              f"({', '.join(field + '.' + f for f in value.__slots__)})")
    raise _cli.UsageError(option, f"a {kind}, not a number")


def field_value(message, field):
    """The number at a dotted field path of a message (checked by check_field)."""
    value = message
    for part in field.split("."):
        value = getattr(value, part)
    return float(value)


class Series:
    """The samples of one topic: stamps and the chosen fields (and the tip's path), and per field
    the count of values that are not finite: (nan, inf)."""

    def __init__(self, topic, fields, path):
        self.topic = topic
        self.fields = list(fields)
        self.path = path
        self.stamps = []
        self.values = {field: [] for field in self.fields}
        self.path_x, self.path_y = [], []
        self.non_finite = {field: (0, 0) for field in self.fields + (PATH_FIELDS if path else [])}
        #: per field, the count of finite values beyond +-PLOT_RANGE (not drawn either)
        self.beyond = {field: 0 for field in self.non_finite}

    def _count(self, field, value):
        if not math.isfinite(value):
            nan, inf = self.non_finite[field]
            self.non_finite[field] = (nan + 1, inf) if math.isnan(value) else (nan, inf + 1)
        elif abs(value) > PLOT_RANGE:
            self.beyond[field] += 1

    def add(self, message):
        values = {field: field_value(message, field) for field in self.fields}  # all or nothing
        self.stamps.append(message.header.stamp.to_sec())
        for field, value in values.items():
            self.values[field].append(value)
            self._count(field, value)
        if self.path:
            self.path_x.append(message.contact_point.x)
            self.path_y.append(message.contact_point.y)
            self._count(PATH_FIELDS[0], message.contact_point.x)
            self._count(PATH_FIELDS[1], message.contact_point.y)

    def __len__(self):
        return len(self.stamps)

    def warnings(self):
        """One line per field with values that are not finite, naming it and counting them."""
        lines = [f"{self.topic}: {field}: {nan + inf} of {len(self)} values are not finite ({nan} nan, {inf} inf); "
                 "not drawn" for field, (nan, inf) in self.non_finite.items() if nan + inf]
        return lines + [f"{self.topic}: {field}: {count} of {len(self)} values lie beyond +-{PLOT_RANGE:g}, where a "
                        "plot's axis cannot be scaled; not drawn" for field, count in self.beyond.items() if count]


PATH_FIELDS = ["contact_point.x", "contact_point.y"]

#: The largest magnitude drawn: matplotlib's axis limits, margins and ticks subtract and scale
#: the data's extremes, and overflowed (then raised IndexError) for a series from -1e308 to 1e308.
PLOT_RANGE = 1e300


#: The first line of every bag rosbag reads (format 2.0).
BAG_MAGIC = b"#ROSBAG V2.0\n"


def read_bag(path, topics, fields, show_path):
    """Series of every topic from a bag (rosbag); UsageError (a ValueError) naming --bag or
    --topic if the file is not a regular file or not a bag, or a topic holds no TopState."""
    import rosbag
    from spinning_top.msg import TopState

    what = _cli.short_path(path)
    try:
        mode = os.stat(path).st_mode
    except OSError as error:
        raise _cli.UsageError("--bag", f"cannot read {what}: {error.strerror}") from None
    if not stat.S_ISREG(mode):  # /dev/zero or a FIFO would be read forever
        raise _cli.UsageError("--bag", f"{what} is not a regular file")
    try:
        with open(path, "rb") as f:
            magic = f.read(len(BAG_MAGIC))
    except OSError as error:
        raise _cli.UsageError("--bag", f"cannot read {what}: {error.strerror}") from None
    if magic != BAG_MAGIC:
        raise _cli.UsageError("--bag", f"{what} is not a ROS bag "
                              f"(it does not start with {BAG_MAGIC.decode().strip()!r})")
    series = {topic: Series(topic, fields, show_path) for topic in topics}
    try:
        with rosbag.Bag(path) as bag:
            found = bag.get_type_and_topic_info().topics
            # rosbag record keeps a topic's name as it was given: the launch file's recorder names
            # the node's topics relatively (spinning_top/state), so that it works under a
            # namespace. A requested topic matches its stored name with or without the leading '/'.
            stored = {}
            for topic in topics:
                bare = topic.lstrip("/")
                stored[topic] = next((name for name in (topic, bare, "/" + bare) if name in found), topic)
            requested = {name: topic for topic, name in stored.items()}
            for topic, name in stored.items():
                if name in found and found[name].msg_type != TopState._type:
                    raise _cli.UsageError(f"--topic {_cli.short(topic, quote=False)}",
                                          f"holds {found[name].msg_type} messages in the bag, not {TopState._type}")
            checked = {TopState._md5sum}
            for name, message, _ in bag.read_messages(topics=list(requested)):
                if message._md5sum not in checked:  # recorded with another definition of TopState
                    for field in fields:
                        check_field(type(message), field)
                    checked.add(message._md5sum)
                series[requested[name]].add(message)
    except _cli.UsageError:
        raise
    except rosbag.ROSBagException as error:  # not a bag, or a damaged one
        raise _cli.UsageError("--bag", f"{what}: {error}") from None
    except OSError as error:
        raise _cli.UsageError("--bag", f"cannot read {what}: {error.strerror or error}") from None
    except Exception as error:  # rosbag's decoding of a damaged record: struct, genpy, ... errors
        raise _cli.UsageError("--bag", f"{what}: a damaged bag ({type(error).__name__}: {error})") from None
    empty = [topic for topic, s in series.items() if len(s) == 0]
    if empty:
        raise _cli.UsageError(f"--topic {', '.join(empty)}", f"no message in {what}")
    return [series[topic] for topic in topics]


def label(field, series=()):
    unit = UNITS.get(field.split(".")[0])
    text = f"{field} [{unit}]" if unit else field
    hidden = sum(sum(s.non_finite.get(field, (0, 0))) for s in series)
    beyond = sum(s.beyond.get(field, 0) for s in series)
    return (text + (f"\n({hidden} not finite, not drawn)" if hidden else "") +
            (f"\n({beyond} beyond +-{PLOT_RANGE:g}, not drawn)" if beyond else ""))


def _finite(values):
    """The values with nan in place of +-inf and of values beyond +-PLOT_RANGE (drawn as gaps, as
    nan is)."""
    return [v if math.isfinite(v) and abs(v) <= PLOT_RANGE else math.nan for v in values]


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
            axis.plot(s.stamps, _finite(s.values[field]), lw=0.9, label=s.topic)
        axis.set_ylabel(label(field, series))
        axis.set_xlabel("stamp [s]")
        axis.grid(alpha=0.3)
    if series[0].path:
        axis = axes[-1]
        for s in series:
            axis.plot(_finite(s.path_x), _finite(s.path_y), lw=0.7, label=s.topic)
        axis.set_xlabel(label(PATH_FIELDS[0], series))
        axis.set_ylabel(label(PATH_FIELDS[1], series))
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
        raise ValueError(f"no ROS master at {rosgraph.get_master_uri()}: start the node, or give --bag")
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
        raise _cli.UsageError(f"--topic {', '.join(empty)}", "no message (is the node running? rostopic list)")
    return series


def _check_arguments(args):
    """Topics, fields and the output, refused before anything is read or subscribed to."""
    from spinning_top.msg import TopState

    import rosgraph.names

    topics = args.topic or [DEFAULT_TOPIC]
    for i, topic in enumerate(topics):
        if not topic or not rosgraph.names.is_legal_name(topic):
            raise _cli.UsageError("--topic", f"{_cli.short(topic)} is not a ROS topic name")
        if topic in topics[:i]:
            raise _cli.UsageError(f"--topic {_cli.short(topic, quote=False)}", "given twice")
    fields = [f.strip() for f in args.fields.split(",")] if args.fields.strip() else []
    for i, field in enumerate(fields):
        if not field:
            raise _cli.UsageError("--fields", f"an empty field in {_cli.short(args.fields)}")
        if field in fields[:i]:
            raise _cli.UsageError(f"--fields {_cli.short(field, quote=False)}", "given twice")
        check_field(TopState, field)
    if not fields and not args.path:
        raise _cli.UsageError("--fields", "nothing to plot: give --fields or --path")
    if args.duration is not None and not args.duration > 0:
        raise _cli.UsageError("--duration", f"must be > 0 s, got {args.duration:.6g}")
    if args.bag is None and args.duration is None and args.no_show:
        raise _cli.UsageError("--no-show", "live without a window needs --duration")
    if args.output is not None and not args.output:
        raise _cli.UsageError("--output", "an empty file name")
    fmt = _cli.check_output("--output", args.output, _cli.figure_formats()) if args.output else None
    return topics, fields, fmt


def main(argv=None):
    parser = _cli.Parser(prog="rosrun spinning_top plot", error_prog="plot", description=__doc__.split("\n\n")[0],
                         formatter_class=argparse.RawDescriptionHelpFormatter,
                         epilog="\n\n".join(__doc__.split("\n\n")[1:]))
    parser.add_argument("--bag", help="read this bag instead of subscribing")
    parser.add_argument("--topic", action="append", help=f"TopState topic, repeatable (default {DEFAULT_TOPIC})")
    parser.add_argument("--fields", default=",".join(DEFAULT_FIELDS),
                        help="comma-separated numeric fields of TopState, dots for nested ones (default %(default)s)")
    parser.add_argument("--path", action="store_true", help="add the tip's path on the floor")
    parser.add_argument("--duration", type=float, help="live: wall seconds to collect (default: until Ctrl-C "
                        "or the window closes)")
    parser.add_argument("--output", help="save the figure to exactly this file, in the format of its extension "
                        "(.png, .svg, .pdf, ...)")
    parser.add_argument("--no-show", action="store_true", help="do not open a window")
    args = parser.parse_args(argv)

    def fail(message):
        return _cli.fail("plot", message)

    import matplotlib

    show = not args.no_show and bool(os.environ.get("DISPLAY"))
    if not show:
        matplotlib.use("Agg")
    try:
        topics, fields, fmt = _check_arguments(args)
    except _cli.UsageError as error:
        return fail(error)
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
        return fail(error)
    for s in series:
        for warning in s.warnings():
            print(f"plot: warning: {warning}", file=sys.stderr)
    figure = draw(series)
    for s in series:
        print(f"plot: {s.topic}: {len(s)} messages, stamps {s.stamps[0]:.6f} to {s.stamps[-1]:.6f} s")
    if args.output:
        try:
            _cli.write_file("--output", args.output, _cli.figure_bytes(figure, fmt, dpi=110))
        except _cli.UsageError as error:
            return fail(error)
        print(f"plot: wrote {args.output}")
    if show:
        plt.ioff()
        plt.show()
    return 0


if __name__ == "__main__":
    sys.exit(main())
