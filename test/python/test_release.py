"""What a release needs of the package's metadata (issue 20, items 5 and 8): package.xml's keys
resolve with rosdep on Ubuntu 20.04 and Debian 12, its declarations are complete, CHANGELOG.rst is
catkin's and names package.xml's version, catkin_lint -W2 finds nothing, the benchmarks are not
part of `all`."""
import os
import pathlib
import re
import shutil
import subprocess
from urllib.parse import urlparse

import pytest
from catkin_pkg.changelog import get_changelog_from_path
from catkin_pkg.package import parse_package

#: Every key package.xml may use, as ros/rosdistro resolves it for Ubuntu 20.04 (focal) and
#: Debian 12 (bookworm), read from ros/rosdistro at 8468e88 (2026-08-22): "ros" for a package
#: released in Noetic (noetic/distribution.yaml), else the Debian/Ubuntu packages of its rule in
#: rosdep/base.yaml or rosdep/python.yaml (focal, bookworm). A new dependency is added here once
#: checked there. python3-dask and python3-distributed have no rule (hence optional, not declared).
ROSDEP = {
    **{name: "ros" for name in (
        "catkin", "message_generation", "message_runtime", "roscpp", "geometry_msgs", "visualization_msgs",
        "std_msgs", "std_srvs", "rosgraph_msgs", "diagnostic_msgs", "diagnostic_updater", "dynamic_reconfigure",
        "tf2", "tf2_ros", "tf2_msgs", "xmlrpcpp", "rosbag", "rosgraph", "rospy", "rviz", "roslaunch", "rostest",
        "rosunit")},
    "python3-setuptools": ("python3-setuptools", "python3-setuptools"),
    "pybind11-dev": ("pybind11-dev", "pybind11-dev"),
    "python3-dev": ("python3-dev", "python3-dev"),
    "libboost-dev": ("libboost-dev", "libboost-dev"),
    "eigen": ("libeigen3-dev", "libeigen3-dev"),
    "yaml-cpp": ("libyaml-cpp-dev", "libyaml-cpp-dev"),
    "gtest": ("libgtest-dev", "libgtest-dev"),
    "python3-numpy": ("python3-numpy", "python3-numpy"),
    "python3-pandas": ("python3-pandas", "python3-pandas"),
    "python3-scipy": ("python3-scipy", "python3-scipy"),
    "python3-matplotlib": ("python3-matplotlib", "python3-matplotlib"),
    "python3-tqdm": ("python3-tqdm", "python3-tqdm"),
    "python3-pytest": ("python3-pytest", "python3-pytest"),
    "python3-yaml": ("python3-yaml", "python3-yaml"),
}
DEPENDENCY_KINDS = ("buildtool_depends", "build_depends", "build_export_depends", "exec_depends", "test_depends")


@pytest.fixture(scope="module")
def package(source_dir):
    package = parse_package(str(source_dir / "package.xml"))
    package.validate()
    return package


def names(package, kind):
    return {d.name for d in getattr(package, kind)}


def test_every_dependency_key_resolves_with_rosdep_on_focal_and_bookworm(package):
    unchecked = {kind: sorted(names(package, kind) - set(ROSDEP)) for kind in DEPENDENCY_KINDS}
    assert not any(unchecked.values()), unchecked
    assert "python3-dask" not in ROSDEP and "python3-distributed" not in ROSDEP


def test_package_xml_declares_what_the_package_uses(package):
    assert {u.type: urlparse(u.url).scheme for u in package.urls} == \
        {"website": "https", "repository": "https", "bugtracker": "https"}
    assert "rosgraph" in names(package, "exec_depends")          # plot.py
    assert {"tf2_msgs", "python3-yaml"} <= names(package, "test_depends")
    assert "python3-dev" in names(package, "build_depends")      # the pybind11 module
    assert "message_runtime" in names(package, "build_export_depends") & names(package, "exec_depends")
    # Boost: the benchmarks' headers only (Boost.Odeint), not a dependency of what is installed.
    assert not any("boost" in name for kind in DEPENDENCY_KINDS if kind != "build_depends"
                   for name in names(package, kind))
    assert {n for n in names(package, "build_depends") if "boost" in n} == {"libboost-dev"}
    # Dask is optional (README): no key.
    assert not {n for kind in DEPENDENCY_KINDS for n in names(package, kind) if "dask" in n or "distributed" in n}
    # Ubuntu 20.04's versions at least (README, "Requirements and versions").
    versions = {d.name: d.version_gte for d in package.exec_depends}
    assert versions["python3-numpy"] == "1.17" and versions["python3-pandas"] == "0.25"
    assert versions["python3-scipy"] == "1.3" and versions["python3-matplotlib"] == "3.1"


def test_changelog_is_catkins_with_the_package_version_first(package, source_dir):
    changelog = get_changelog_from_path(str(source_dir / "CHANGELOG.rst"), "spinning_top")
    assert changelog is not None, "CHANGELOG.rst is not in catkin's format"
    versions = [version for version, _, _ in changelog.foreach_version()]
    assert versions[0] == package.version, (versions, package.version)
    text = (source_dir / "CHANGELOG.rst").read_text()
    assert re.search(r"^" + re.escape(package.version) + r" \(\d{4}-\d{2}-\d{2}\)\n-+\n", text, re.M)
    assert text.startswith("^^^^"), "catkin_generate_changelog's title"


def test_catkin_lint_w2_finds_nothing(source_dir, tmp_path):
    if not shutil.which("catkin_lint"):
        pytest.fail("catkin_lint is missing: apt-get install catkin-lint (scripts/setup.sh installs it)")
    # catkin_lint compares the folder's name with the package's: a checkout may be named otherwise.
    link = tmp_path / "spinning_top"
    link.symlink_to(source_dir.resolve(), target_is_directory=True)
    # No rosdistro download (ROS_DISTRO), and the checkout itself not on ROS_PACKAGE_PATH (sourcing
    # the devel space puts it there): only the link is this package.
    env = {k: v for k, v in os.environ.items() if k != "ROS_DISTRO"}
    env["ROS_PACKAGE_PATH"] = os.pathsep.join(
        p for p in env.get("ROS_PACKAGE_PATH", "").split(os.pathsep)
        if p and not os.path.realpath(p).startswith(os.path.realpath(source_dir)))
    result = subprocess.run(["catkin_lint", "-W2", "--strict", str(link)], capture_output=True, text=True,
                            timeout=120, env=env)
    assert result.returncode == 0 and "found 0 problems" in result.stderr, result.stdout + result.stderr
    assert result.stdout.strip() == "", result.stdout


def test_benchmarks_are_not_built_by_all():
    # The package's build folder, where test/CMakeLists.txt runs the tests (Makefile generator).
    binary_dir = os.environ.get("SPINNING_TOP_BINARY_DIR")
    if not binary_dir:
        pytest.skip("SPINNING_TOP_BINARY_DIR not set (make run_tests sets it)")
    makefile2 = pathlib.Path(binary_dir) / "CMakeFiles/Makefile2"
    if not makefile2.is_file():  # a catkin_make workspace: the workspace's build folder has it
        makefile2 = next((p / "CMakeFiles/Makefile2" for p in pathlib.Path(binary_dir).parents
                          if (p / "CMakeFiles/Makefile2").is_file()), None)
    if makefile2 is None:
        pytest.skip("not a Makefile build")
    # Makefile2's rules "X: Y"; what `all` builds is their closure from "all".
    rules = {}
    for target, prerequisite in re.findall(r"^(\S+): (\S+)$", makefile2.read_text(), re.M):
        rules.setdefault(target, set()).add(prerequisite)
    built, todo = set(), ["all"]
    while todo:
        for prerequisite in rules.get(todo.pop(), ()):
            if prerequisite not in built:
                built.add(prerequisite)
                todo.append(prerequisite)
    assert any("/spinning_top_core.dir/" in target for target in built)
    for benchmark in ("work_precision", "viscous_default", "fuzz_soak", "hop_cost", "extreme_cases", "budget_time"):
        assert not any(f"/{benchmark}.dir/" in target for target in built), benchmark


def _catkin_toplevel():
    """catkin's toplevel.cmake, the CMakeLists.txt of a catkin_make workspace's src folder."""
    prefixes = [p for p in os.environ.get("CMAKE_PREFIX_PATH", "").split(os.pathsep) if p] + ["/opt/ros/noetic", "/usr"]
    for prefix in prefixes:
        path = pathlib.Path(prefix) / "share/catkin/cmake/toplevel.cmake"
        if path.is_file():
            return path
    pytest.fail("catkin's toplevel.cmake not found")


@pytest.mark.parametrize("layout, build_type", [("catkin_make", ""), ("alone", "Release")])
def test_the_build_type_defaults_to_release_only_where_the_package_is_the_project(layout, build_type, source_dir,
                                                                                   tmp_path):
    # Configured only (a few seconds): in a catkin_make workspace the package must leave the
    # workspace's CMAKE_BUILD_TYPE alone (here: none given); built alone, it defaults to Release.
    if layout == "catkin_make":
        src = tmp_path / "src"
        src.mkdir()
        (src / "spinning_top").symlink_to(source_dir.resolve(), target_is_directory=True)
        (src / "CMakeLists.txt").symlink_to(_catkin_toplevel())
    else:
        src = source_dir
    build = tmp_path / "build"
    devel = os.environ.get("SPINNING_TOP_DEVEL", "")
    env = dict(os.environ)
    env["CMAKE_PREFIX_PATH"] = os.pathsep.join(  # not this package's own devel space
        p for p in env.get("CMAKE_PREFIX_PATH", "").split(os.pathsep)
        if p and not (devel and os.path.realpath(p) == os.path.realpath(devel)))
    result = subprocess.run(["cmake", "-S", str(src), "-B", str(build), "-DPYTHON_EXECUTABLE=/usr/bin/python3",
                             f"-DCATKIN_DEVEL_PREFIX={tmp_path / 'devel'}", "-DCATKIN_ENABLE_TESTING=OFF"],
                            capture_output=True, text=True, timeout=300, env=env)
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-3000:]
    cache = (build / "CMakeCache.txt").read_text()
    assert re.search(r"^CMAKE_BUILD_TYPE:STRING=(.*)$", cache, re.M).group(1) == build_type
