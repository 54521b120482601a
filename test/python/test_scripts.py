"""scripts/run.sh and scripts/sweep.sh (issue 20, item 9): catkin's setup.bash reads the
positional parameters of whoever sources it, so `--help` given to a script reached it and came
out as "usage:: command not found". `--help` prints the script's usage and the tool's own help,
without installing or building anything."""
import os
import subprocess

import pytest


@pytest.fixture(scope="module")
def script_env():
    """The test's environment; SPINNING_TOP_DEVEL (the devel space, set by test/CMakeLists.txt)
    tells the scripts where setup.bash is, in a catkin workspace too."""
    env = dict(os.environ)
    if not env.get("SPINNING_TOP_DEVEL"):
        pytest.fail("SPINNING_TOP_DEVEL must name the devel space (its setup.bash)")
    return env


def run_script(source_dir, env, *args):
    return subprocess.run(["bash", str(source_dir / "scripts" / args[0]), *args[1:]], capture_output=True, text=True,
                          timeout=120, env=env, stdin=subprocess.DEVNULL)


@pytest.mark.parametrize("script, expected", [
    # roslaunch --ros-args: the launch file's arguments
    ("run.sh", ["usage: bash scripts/run.sh [NAME:=VALUE ...]", "Arguments of spinning_top.launch", "scene:",
                "rviz:"]),
    # python3 -m spinning_top.sweep --help
    ("sweep.sh", ["usage: sweep [-h] --config CONFIG", "--vary KEY=SPEC", "--scheduler SCHEDULER"]),
])
@pytest.mark.parametrize("flag", ["--help", "-h"])
def test_help_prints_the_usage_and_the_tools_help(script, expected, flag, source_dir, script_env):
    result = run_script(source_dir, script_env, script, flag)
    both = result.stdout + result.stderr
    assert "command not found" not in both
    assert result.returncode == 0, both
    for text in expected:
        assert text in result.stdout, (text, both)
    assert "setup.sh:" not in both and "Building" not in both  # nothing installed or built


def test_devel_setup_is_sourced_without_the_callers_arguments(source_dir, script_env):
    # What both scripts do before running their tool, with arguments that catkin's setup.sh
    # would take for its own (--help, --extend, --local): the environment is the devel space's.
    script = ('source "$0/scripts/env.sh"; set -- --help --extend --local; spinning_top_source_devel; '
              'echo "args: $*"; echo "ROS_PACKAGE_PATH=$ROS_PACKAGE_PATH"')
    result = subprocess.run(["bash", "-euo", "pipefail", "-c", script, str(source_dir)], capture_output=True,
                            text=True, timeout=60, env=script_env)
    assert result.returncode == 0, result.stderr
    assert "command not found" not in result.stdout + result.stderr
    lines = result.stdout.splitlines()
    assert lines[-2] == "args: --help --extend --local"  # the caller's, untouched
    assert lines[-1].startswith("ROS_PACKAGE_PATH=") and len(lines[-1]) > len("ROS_PACKAGE_PATH=")
