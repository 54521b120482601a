"""The plot tool (`rosrun spinning_top plot`, python/spinning_top/plot.py) against bad input
(issue 19): it writes exactly the file asked for or refuses, in one line naming the option (exit
status 2); a field is a numeric field of TopState, nothing else; non-finite values are named and
counted. On a bag written here (no ROS master needed)."""
import math
import os
import subprocess
import sys

import pytest

rosbag = pytest.importorskip("rosbag")
rospy = pytest.importorskip("rospy")
from spinning_top.msg import TopState  # noqa: E402  (generated: the build's devel space)

from spinning_top import plot  # noqa: E402

TOPIC = "/spinning_top/state"


@pytest.fixture(scope="module")
def bag(tmp_path_factory):
    """20 states 10 ms apart; energy nan at the 6th and inf at the 7th, as a failing run's could be."""
    path = tmp_path_factory.mktemp("bag") / "top.bag"
    with rosbag.Bag(str(path), "w") as b:
        for i in range(20):
            m = TopState()
            m.header.stamp = rospy.Time(0, i * 10_000_000)
            m.tilt, m.energy, m.normal_force = 0.01 * i, 1.0 - 1e-3 * i, 0.9
            m.energy = {5: math.nan, 6: math.inf}.get(i, m.energy)
            b.write(TOPIC, m, m.header.stamp)
    return str(path)


@pytest.fixture
def plot_main(capsys, monkeypatch, tmp_path, bag):
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("DISPLAY", raising=False)

    def main(*arguments, bag_path=bag):
        status = plot.main(["--bag", bag_path, "--no-show", *arguments])
        out, err = capsys.readouterr()
        return status, out.splitlines(), err.splitlines()
    return main


def test_writes_exactly_the_file_asked_for(plot_main, tmp_path):
    status, out, err = plot_main("--fields", "tilt,angular_velocity.z", "--output", "top.svg")
    assert (status, err) == (0, [])
    assert out[-1] == "plot: wrote top.svg"
    assert os.listdir(tmp_path) == ["top.svg"] and (tmp_path / "top.svg").read_bytes().startswith(b"<?xml")


@pytest.mark.parametrize("output, message", [
    ("top", "--output: 'top' has no extension; give one of "),
    ("top.xyz", "--output: 'top.xyz' has extension .xyz; give one of "),
    ("dir.png", "--output: 'dir.png' is a directory; give a file name"),
    ("missing/top.png", "--output: 'missing/top.png': no directory "),
    ("", "--output: an empty file name"),
])
def test_refuses_an_output_it_would_not_write_as_asked(plot_main, tmp_path, output, message):
    (tmp_path / "dir.png").mkdir()
    # Checked before the bag is read: the error names --output, not the missing bag.
    status, out, err = plot_main("--output", output, bag_path=str(tmp_path / "no.bag"))
    assert (status, out) == (2, [])
    assert len(err) == 1 and err[0].startswith(f"plot: error: {message}"), err
    assert sorted(os.listdir(tmp_path)) == ["dir.png"]


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="needs /dev/full")
def test_a_device_is_written_as_asked_or_the_error_names_output(plot_main, tmp_path):
    existed = os.path.exists("/dev/full.png")
    try:
        status, out, err = plot_main("--output", "/dev/full")  # no extension: not /dev/full.png
        assert (status, out) == (2, [])
        assert len(err) == 1 and err[0].startswith("plot: error: --output: '/dev/full' has no extension")
        assert os.path.exists("/dev/full.png") == existed
    finally:
        if not existed and os.path.exists("/dev/full.png"):
            os.remove("/dev/full.png")  # what the tool wrote before it checked
    (tmp_path / "full.png").symlink_to("/dev/full")  # a name with an extension, on a full device
    status, out, err = plot_main("--fields", "tilt", "--output", "full.png")
    assert status == 2 and not any("wrote" in line for line in out)
    assert err == ["plot: error: --output: cannot write 'full.png': No space left on device"]
    assert os.readlink(tmp_path / "full.png") == "/dev/full"


@pytest.mark.parametrize("field, message", [
    ("energy.imag", "--fields energy.imag: energy is a float64, it has no field imag"),
    ("energy.real", "--fields energy.real: energy is a float64, it has no field real"),
    ("tilt.__class__", "--fields tilt.__class__: tilt is a float64, it has no field __class__"),
    ("__class__", "--fields __class__: TopState has no field __class__"),
    ("_type", "--fields _type: TopState has no field _type"),
    ("nonsense", "--fields nonsense: TopState has no field nonsense"),
    ("event", "--fields event: a string, not a number"),
    ("contact_point", "--fields contact_point: a geometry_msgs/Point, not a number; give one of its fields "
                      "(contact_point.x, contact_point.y, contact_point.z)"),
    ("header.stamp", "--fields header.stamp: a time, not a number"),
    ("tilt,energy,tilt", "--fields tilt: given twice"),
])
def test_fields_are_the_messages_numeric_fields(plot_main, field, message):
    status, out, err = plot_main("--fields", field, "--output", "bad.png")
    assert (status, out) == (2, [])
    assert err == [f"plot: error: {message}"]
    assert not os.path.exists("bad.png")


def test_non_finite_values_are_named_and_counted(plot_main):
    status, out, err = plot_main("--fields", "tilt,energy", "--output", "top.png")
    assert status == 0
    assert err == [f"plot: warning: {TOPIC}: energy: 2 of 20 values are not finite (1 nan, 1 inf); not drawn"]
    assert out[-1] == "plot: wrote top.png"


def test_the_figure_marks_non_finite_values(bag):
    (series,) = plot.read_bag(bag, [TOPIC], ["tilt", "energy"], False)
    assert series.non_finite == {"tilt": (0, 0), "energy": (1, 1)}
    figure = plot.draw([series])
    tilt_axis, energy_axis = figure.axes
    assert "not finite" not in tilt_axis.get_ylabel()
    assert "2 not finite, not drawn" in energy_axis.get_ylabel()
    (line,) = energy_axis.get_lines()
    assert sum(not math.isfinite(y) for y in line.get_ydata()) == 2


def test_values_beyond_what_an_axis_scales_are_named_counted_and_not_drawn(plot_main, tmp_path):
    """A tilt of -1e308 and 1e308 took matplotlib's axis into an overflow and an IndexError (a
    traceback, exit 1; the attack's seed 1206). +-1e300 is still drawn."""
    path = tmp_path / "huge.bag"
    with rosbag.Bag(str(path), "w") as b:
        for i, tilt in enumerate([0.1, 1e308, -1e308, 0.2, 1e300, -1e300, 5e-324]):
            m = TopState()
            m.header.stamp = rospy.Time(0, (i + 1) * 10_000_000)
            m.tilt = tilt
            b.write(TOPIC, m, m.header.stamp)
    status, out, err = plot_main("--fields", "tilt", "--output", "huge.png", bag_path=str(path))
    assert status == 0
    assert err == [f"plot: warning: {TOPIC}: tilt: 2 of 7 values lie beyond +-1e+300, where a plot's axis cannot "
                   "be scaled; not drawn"]
    assert out[-1] == "plot: wrote huge.png" and os.path.getsize("huge.png") > 0
    (series,) = plot.read_bag(str(path), [TOPIC], ["tilt"], False)
    (axis,) = plot.draw([series]).axes
    assert "2 beyond +-1e+300, not drawn" in axis.get_ylabel()
    (line,) = axis.get_lines()
    assert sum(math.isnan(y) for y in line.get_ydata()) == 2


def test_bad_topics_and_bags_are_refused(plot_main, tmp_path, bag):
    status, _, err = plot_main("--topic", TOPIC, "--topic", TOPIC)
    assert (status, err) == (2, [f"plot: error: --topic {TOPIC}: given twice"])
    status, _, err = plot_main("--topic", "a b")
    assert (status, err) == (2, ["plot: error: --topic: 'a b' is not a ROS topic name"])
    status, _, err = plot_main("--topic", "/other")
    assert (status, err) == (2, [f"plot: error: --topic /other: no message in '{bag}'"])
    (tmp_path / "program.bag").write_bytes(open(sys.executable, "rb").read(4096))
    status, _, err = plot_main(bag_path="program.bag")
    assert (status, err) == (2, ["plot: error: --bag: 'program.bag' is not a ROS bag (it does not start with "
                                 "'#ROSBAG V2.0')"])
    status, _, err = plot_main(bag_path=str(tmp_path))
    assert (status, err) == (2, [f"plot: error: --bag: '{tmp_path}' is not a regular file"])
    missing = tmp_path / "none.bag"
    status, _, err = plot_main(bag_path=str(missing))
    assert (status, err) == (2, [f"plot: error: --bag: cannot read '{missing}': No such file or directory"])


def test_an_endless_bag_is_refused_at_once():
    # /dev/zero used to be read forever; the guard's timeout only stops a hang, it is not a limit.
    result = subprocess.run([sys.executable, "-m", "spinning_top.plot", "--bag", "/dev/zero", "--no-show"],
                            capture_output=True, text=True, timeout=120)
    assert result.returncode == 2
    assert result.stderr == "plot: error: --bag: '/dev/zero' is not a regular file\n"


def test_a_write_cut_short_leaves_no_partial_file(bag, tmp_path):
    import resource
    import signal

    from spinning_top import _cli

    (series,) = plot.read_bag(bag, [TOPIC], ["tilt"], False)
    png = _cli.figure_bytes(plot.draw([series]), "png")
    assert len(png) > 8192
    (tmp_path / "old.png").write_bytes(b"old")
    soft, hard = resource.getrlimit(resource.RLIMIT_FSIZE)
    handler = signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    resource.setrlimit(resource.RLIMIT_FSIZE, (4096, hard))  # files of 4 kB at most: the write fails part way
    try:
        errors = []
        for name in ("new.png", "old.png"):
            with pytest.raises(_cli.UsageError) as refused:
                _cli.write_file("--output", tmp_path / name, png)
            errors.append(str(refused.value))
    finally:
        resource.setrlimit(resource.RLIMIT_FSIZE, (soft, hard))
        signal.signal(signal.SIGXFSZ, handler)
    assert errors == [f"--output: cannot write '{tmp_path / 'new.png'}': File too large",
                      f"--output: cannot write '{tmp_path / 'old.png'}': File too large (left empty, not half written)"]
    assert os.listdir(tmp_path) == ["old.png"] and (tmp_path / "old.png").read_bytes() == b""


def test_reads_a_topic_recorded_by_a_relative_name(tmp_path, capsys, monkeypatch):
    """The launch file's recorder names the node's topics relatively (spinning_top/state, issue 20:
    it works under a namespace), and rosbag keeps the name as given: the default --topic
    /spinning_top/state still finds them, and the series is named as asked."""
    path = tmp_path / "relative.bag"
    with rosbag.Bag(str(path), "w") as b:
        for i in range(5):
            m = TopState()
            m.header.stamp = rospy.Time(0, i * 10_000_000)
            m.tilt = 0.01 * i
            b.write(TOPIC.lstrip("/"), m, m.header.stamp)
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("DISPLAY", raising=False)
    status = plot.main(["--bag", str(path), "--no-show", "--fields", "tilt", "--output", "top.svg"])
    out, err = capsys.readouterr()
    assert (status, err) == (0, ""), err
    assert out.splitlines()[-1] == "plot: wrote top.svg"
