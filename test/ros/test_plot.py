#!/usr/bin/env python3
"""`rosrun spinning_top plot` on a bag recorded here from a running node (plot_bag.test)."""
import os
import shutil
import subprocess
import tempfile
import unittest

import rosbag
import rostest

TOPIC = "/spinning_top/state"
FIELDS = ["normal_force", "tilt", "energy", "dissipated_energy"]


class PlotBag(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.directory = tempfile.mkdtemp(prefix="spinning_top_plot_")
        cls.bag = os.path.join(cls.directory, "top.bag")
        subprocess.run(["rosbag", "record", "-q", "-O", cls.bag, "--duration=2", TOPIC], check=True, timeout=60,
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        with rosbag.Bag(cls.bag) as bag:
            cls.messages = [m for _, m, _ in bag.read_messages(topics=[TOPIC])]

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.directory)

    def plot(self, *arguments):
        return subprocess.run(["rosrun", "spinning_top", "plot", "--bag", self.bag, "--no-show", *arguments],
                              capture_output=True, text=True, timeout=120)

    def test_writes_a_png_of_the_bag(self):
        self.assertGreater(len(self.messages), 500)  # 2 s at 500 Hz, minus the start
        png = os.path.join(self.directory, "top.png")
        result = self.plot("--fields", ",".join(FIELDS), "--path", "--output", png)
        self.assertEqual(result.returncode, 0, result.stderr)
        self.assertIn(f"{TOPIC}: {len(self.messages)} messages", result.stdout)
        with open(png, "rb") as f:
            self.assertEqual(f.read(8), b"\x89PNG\r\n\x1a\n")
        self.assertGreater(os.path.getsize(png), 20000)

    def test_the_figure_holds_the_bag_series(self):
        from spinning_top import plot

        series = plot.read_bag(self.bag, [TOPIC], FIELDS, True)
        figure = plot.draw(series)
        self.assertEqual(len(figure.axes), len(FIELDS) + 1)
        for axis, field in zip(figure.axes, FIELDS):
            (line,) = axis.get_lines()
            self.assertEqual(list(line.get_ydata()), [getattr(m, field) for m in self.messages])
            self.assertEqual(list(line.get_xdata()), [m.header.stamp.to_sec() for m in self.messages])
        (path,) = figure.axes[-1].get_lines()
        self.assertEqual(list(path.get_xdata()), [m.contact_point.x for m in self.messages])
        # Physics in the series: R > 0 on a viscous floor at the default spin, and the energy
        # balance E + W constant to round-off (dop853 at 1e-13 per step; 1e-9 of E over 2 s).
        self.assertTrue(all(m.normal_force > 0.0 for m in self.messages))
        balance = [m.energy + m.dissipated_energy for m in self.messages]
        self.assertLess(max(balance) - min(balance), 1e-9 * abs(balance[0]))
        self.assertGreater(self.messages[-1].dissipated_energy, 0.0)

    def test_live_from_the_running_node(self):
        png = os.path.join(self.directory, "live.png")
        result = subprocess.run(["rosrun", "spinning_top", "plot", "--duration", "2", "--no-show", "--path",
                                 "--output", png], capture_output=True, text=True, timeout=120)
        self.assertEqual(result.returncode, 0, result.stderr)
        count = int(result.stdout.split(f"{TOPIC}: ")[1].split(" messages")[0])
        self.assertGreater(count, 500)  # 2 s of wall time at 500 Hz and real-time factor 1
        self.assertGreater(os.path.getsize(png), 20000)

    def test_refuses_a_file_that_is_not_a_bag(self):
        not_a_bag = os.path.join(self.directory, "not_a.bag")
        with open(not_a_bag, "w") as f:
            f.write("garbage\n")
        result = subprocess.run(["rosrun", "spinning_top", "plot", "--bag", not_a_bag, "--no-show"],
                                capture_output=True, text=True, timeout=120)
        self.assertEqual(result.returncode, 2, result.stderr)
        self.assertIn(f"plot: error: --bag: '{not_a_bag}' is not a ROS bag", result.stderr)
        self.assertNotIn("Traceback", result.stderr)

    def test_refuses_a_field_that_is_not_a_number(self):
        for field in ("nonsense", "event", "contact_point"):
            result = self.plot("--fields", field, "--output", os.path.join(self.directory, "bad.png"))
            self.assertEqual(result.returncode, 2, field)
            self.assertIn(field, result.stderr)
        self.assertFalse(os.path.exists(os.path.join(self.directory, "bad.png")))


if __name__ == "__main__":
    rostest.rosrun("spinning_top", "plot_bag", PlotBag)
