"""The shipped launch files compose (issue 20, items 2 to 4): parsed by roslaunch itself, as
included under <group ns="r1">, the recorder and rviz find the node's topics in that namespace,
and nothing needs HOME (systemd, robot_upstart)."""
import json
import os
import subprocess

import pytest
import yaml

from conftest import SOURCE_DIR

LAUNCH = SOURCE_DIR / "launch"
CONFIG = SOURCE_DIR / "config"
GLOBAL_TOPICS = {"/tf", "/tf_static", "/clock", "/diagnostics"}

# Runs in a child without HOME: roslaunch's loader (what `roslaunch` and roslaunch-check run)
# on an XML string, printing each node's namespace, name, args and working directory.
LOADER = r"""
import json, sys
import roslaunch.config
config = roslaunch.config.load_config_default([], None, roslaunch_strs=[sys.argv[1]])
print(json.dumps([{"namespace": n.namespace, "name": n.name, "package": n.package, "args": n.args,
                   "cwd": n.cwd} for n in config.nodes]))
"""


def load(xml, home=False):
    """The nodes roslaunch would start for `xml`, loaded with HOME unset unless `home`."""
    env = {key: value for key, value in os.environ.items() if home or key != "HOME"}
    env["ROS_PACKAGE_PATH"] = os.pathsep.join(filter(None, [str(SOURCE_DIR), env.get("ROS_PACKAGE_PATH")]))
    done = subprocess.run(["/usr/bin/python3", "-c", LOADER, xml],
                          env=env, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr[-2000:]
    return {node["name"]: node for node in json.loads(done.stdout.strip().splitlines()[-1])}


def included(launch, ns="r1", **args):
    passed = "".join(f'<arg name="{key}" value="{value}"/>' for key, value in args.items())
    inner = f'<include file="{LAUNCH / launch}">{passed}</include>'
    return f'<launch><group ns="{ns}">{inner}</group></launch>' if ns else f"<launch>{inner}</launch>"


def resolve(name, namespace):
    return name if name.startswith("/") else namespace.rstrip("/") + "/" + name


@pytest.mark.parametrize("launch, args", [
    ("spinning_top.launch", {}),
    ("spinning_top.launch", {"record": "true"}),
    ("spinning_top.launch", {"record": "true", "rviz": "true"}),
    ("two_tops.launch", {"rviz": "true"}),
])
def test_launch_parses_without_home(launch, args):
    """Item 4: `$(env HOME)` in the bag default broke the launch without HOME, record:=false too."""
    nodes = load(included(launch, ns=None, **args))
    assert "spinning_top" in nodes


def test_recorder_records_the_nodes_topics_under_a_namespace():
    """Item 2: the recorder's topics, resolved in its namespace, are the node's (absolute
    /spinning_top/... names left the node waiting for ever), plus the global ones."""
    nodes = load(included("spinning_top.launch", record="true", bag="/tmp/x.bag"), home=True)
    record, node = nodes["record"], nodes["spinning_top"]
    assert record["namespace"] == node["namespace"] == "/r1/"
    args = record["args"].split()
    assert args[:2] == ["-O", "/tmp/x.bag"]
    topics = {resolve(topic, record["namespace"]) for topic in args[2:]}
    private = "/r1/spinning_top/"
    assert GLOBAL_TOPICS <= topics
    assert topics - GLOBAL_TOPICS == {private + t for t in (
        "contact_point", "normal_force", "twist", "state", "status", "markers", "event", "event_stamped")}
    # ~wait_for_subscriber waits for these two (and /clock): the recorder must subscribe to them.
    assert {private + "contact_point", private + "state", "/clock"} <= topics


def test_default_bag_is_written_in_ros_home():
    """Item 4: a relative default, written in the recorder's working directory, ROS_HOME."""
    record = load(included("spinning_top.launch", ns=None, record="true"))["record"]
    bag = record["args"].split()[1]
    assert not os.path.isabs(bag) and bag.endswith(".bag")
    assert record["cwd"] == "ROS_HOME"


def rviz_topics(name):
    """Every topic or parameter name a display of an rviz config reads."""
    displays = yaml.safe_load((CONFIG / name).read_text())["Visualization Manager"]["Displays"]
    keys = ("Topic", "Marker Topic", "Robot Description")
    return {(d["Class"], d[key]) for d in displays for key in keys if key in d}


@pytest.mark.parametrize("launch, config, expected", [
    ("spinning_top.launch", "spinning_top.rviz",
     {"/r1/spinning_top/markers", "/r1/spinning_top/normal_force", "/r1/spinning_top/robot_description"}),
    ("two_tops.launch", "two_tops.rviz", {f"/r1/spinning_top/{top}/{topic}" for top in ("slow", "fast")
                                          for topic in ("markers", "normal_force")}),
])
def test_rviz_shows_the_node_under_a_namespace(launch, config, expected):
    """Item 3: the configs' names are relative and rviz starts in the node's namespace, so that
    under <group ns="r1"> they resolve to the node's topics (absolute ones showed nothing)."""
    nodes = load(included(launch, rviz="true"), home=True)
    rviz = nodes["rviz"]
    assert rviz["package"] == "rviz"
    assert rviz["namespace"] == "/r1/spinning_top/"
    assert rviz["args"].split()[:1] == ["-d"] and rviz["args"].split()[1].endswith("/config/" + config)
    names = rviz_topics(config)
    assert all(not name.startswith("/") for _, name in names), names
    assert {resolve(name, rviz["namespace"]) for _, name in names} == expected


# The parameters roslaunch would set for an XML string (a child process, like LOADER).
PARAMETERS = r"""
import json, sys
import roslaunch.config
config = roslaunch.config.load_config_default([], None, roslaunch_strs=[sys.argv[1]])
print(json.dumps({name: param.value for name, param in config.params.items()}))
"""


def parameters(xml):
    env = dict(os.environ)
    env["ROS_PACKAGE_PATH"] = os.pathsep.join(filter(None, [str(SOURCE_DIR), env.get("ROS_PACKAGE_PATH")]))
    done = subprocess.run(["/usr/bin/python3", "-c", PARAMETERS, xml], env=env, capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0, done.stderr[-2000:]
    return json.loads(done.stdout.strip().splitlines()[-1])


def test_two_includes_share_one_clock_and_one_use_sim_time():
    """Item 1: spinning_top.launch included twice. Each node's ~publish_clock is auto (one /clock in
    the graph: the first node publishes it, the other follows), not true (both published, and
    /clock went back); with set_use_sim_time:=false an include leaves the global /use_sim_time to
    the including file, so that one include's use_sim_time:=false cannot change it for the other."""
    def group(ns, **args):
        passed = "".join(f'<arg name="{key}" value="{value}"/>' for key, value in args.items())
        return f'<group ns="{ns}"><include file="{LAUNCH / "spinning_top.launch"}">{passed}</include></group>'

    both = parameters(f'<launch>{group("r1")}{group("r2")}</launch>')
    assert both["/r1/spinning_top/publish_clock"] == both["/r2/spinning_top/publish_clock"] == "auto"
    assert both["/use_sim_time"] is True
    composed = parameters('<launch><param name="/use_sim_time" value="true"/>'
                          f'{group("r1", set_use_sim_time="false")}'
                          f'{group("r2", set_use_sim_time="false", use_sim_time="false")}</launch>')
    assert composed["/use_sim_time"] is True
    assert composed["/r1/spinning_top/publish_clock"] == "auto"
    assert composed["/r2/spinning_top/publish_clock"] is False
