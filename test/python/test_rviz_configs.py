"""The shipped rviz configs load (rviz silently falls back to an empty view on a YAML error)
and show the node's topics and frames: relative names (rviz runs in the node's namespace, see
test_launch_files.py), each top labelled by its markers, the floor force at a readable scale."""
import pathlib

import pytest
import yaml

CONFIG = pathlib.Path(__file__).resolve().parents[2] / "config"
MG = 0.1 * 9.80665  # [N] the shipped scenes' weight m g: R stays within 0.9 ... 1.06 N
SPIKE = 8.12  # [N] the largest R of the README's hopping top (frictionless, tilt 0.8, 60 rad/s) at t = 0
TOP_HEIGHT = 0.0267  # [m] the shipped top's body (rim_distance a)
ARROW = 1.3  # rviz's force arrow: a shaft of 1 and a head of 0.3 times scale x |F|


def displays(name):
    return yaml.safe_load((CONFIG / name).read_text())["Visualization Manager"]["Displays"]


@pytest.mark.parametrize("name, marker_topics, force_topics, hidden_frames", [
    ("spinning_top.rviz", {"markers"}, {"normal_force"}, {"contact"}),
    ("two_tops.rviz", {"slow/markers", "fast/markers"}, {"slow/normal_force", "fast/normal_force"},
     {"slow/contact", "fast/contact"}),
])
def test_config_loads_and_shows_the_node(name, marker_topics, force_topics, hidden_frames):
    shown = displays(name)
    markers = [d for d in shown if d["Class"] == "rviz/MarkerArray"]
    assert {d["Marker Topic"] for d in markers} == marker_topics
    assert {d["Topic"] for d in shown if d["Class"] == "rviz/WrenchStamped"} == force_topics
    # Each top's label is a marker above its body; the force is the WrenchStamped display's
    # alone (the markers' own arrow, at the node's ~force_scale, would be a second one).
    for d in markers:
        assert d["Namespaces"]["label"] is True and d["Namespaces"]["force"] is False, d["Name"]
    (tf,) = [d for d in shown if d["Class"] == "rviz/TF"]
    # The TF display's names sat inside the cone (G) and on the world's axes (the pivot).
    assert tf["Show Names"] is False
    assert all(tf["Frames"][frame] == {"Value": False} for frame in hidden_frames)


@pytest.mark.parametrize("name", ["spinning_top.rviz", "two_tops.rviz"])
def test_floor_force_arrow_is_readable(name):
    """Item 12: rviz hides a force arrow shorter than its width (Hide Small Values): at width 0.3
    and 0.05 m/N it drew nothing at m g = 1 N, and 0.53 m at the hopping top's 8 N."""
    wrenches = [d for d in displays(name) if d["Class"] == "rviz/WrenchStamped"]
    assert wrenches
    for d in wrenches:
        scale, width = d["Force Arrow Scale"], d["Arrow Width"]
        assert d.get("Hide Small Values", True) is True  # no stray zero-length arrow in flight
        assert scale * 0.5 * MG > width, "hidden at half the weight"
        # m g: the arrow leaves the translucent body (the tip's vertical meets the rim's plane at
        # a / cos(tilt) = 2.8 cm at the shipped tilt 0.3 rad) by its head at least.
        assert 1.3 * TOP_HEIGHT <= ARROW * scale * MG <= 2 * TOP_HEIGHT, "m g: the arrow's head above the body"
        assert ARROW * scale * SPIKE < 0.53 * 0.75, "the hopping top's 8 N well below the former 0.53 m"
        assert 0.1 * width >= 0.001, "a shaft of at least 1 mm"
