"""The shipped rviz configs load (rviz silently falls back to an empty view on a YAML error)
and show the node's topics and frames."""
import pathlib

import pytest
import yaml

CONFIG = pathlib.Path(__file__).resolve().parents[2] / "config"


def displays(name):
    return yaml.safe_load((CONFIG / name).read_text())["Visualization Manager"]["Displays"]


@pytest.mark.parametrize("name, marker_topics, hidden_frames", [
    ("spinning_top.rviz", {"markers"}, {"contact"}),
    ("two_tops.rviz", {"slow/markers", "fast/markers"}, {"slow/contact", "fast/contact"}),
])
def test_config_loads_and_shows_the_node(name, marker_topics, hidden_frames):
    shown = displays(name)
    assert {d["Marker Topic"] for d in shown if d["Class"] == "rviz/MarkerArray"} == marker_topics
    (tf,) = [d for d in shown if d["Class"] == "rviz/TF"]
    # The contact frames' labels sat on the world's (fixed tip): hidden.
    assert all(tf["Frames"][frame] == {"Value": False} for frame in hidden_frames)
