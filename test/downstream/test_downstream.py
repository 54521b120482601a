"""A downstream catkin package against spinning_top's install space (issue 20, item 7).

The installed headers need C++17 (std::optional). GCC 9, Ubuntu 20.04's (Noetic), compiles C++14
by default; this machine's compiler defaults to C++17, so GCC 9's default is forced here with
CMAKE_CXX_FLAGS=-std=gnu++14, as a Noetic user's package gets it. The package exports the
requirement (cmake/spinning_top-extras.cmake): the downstream package must build, and run.

Lean: the package is installed from its existing build (its cmake_install.cmake, staged with
DESTDIR in a temporary folder; nothing is rebuilt), then one small package is configured and one
file compiled. Run by `make run_tests` (test/CMakeLists.txt: SPINNING_TOP_BINARY_DIR, the package's
build folder) or by hand:
  SPINNING_TOP_BINARY_DIR=build python3 -m pytest test/downstream
"""
import os
import pathlib
import re
import subprocess

import pytest

HERE = pathlib.Path(__file__).resolve().parent
TIMEOUT = 600  # [s] a hang guard only


def run(command, **kwargs):
    result = subprocess.run(command, capture_output=True, text=True, timeout=TIMEOUT, **kwargs)
    assert result.returncode == 0, f"{' '.join(map(str, command))} failed:\n{result.stdout[-4000:]}\n{result.stderr[-4000:]}"
    return result


@pytest.fixture(scope="module")
def binary_dir():
    path = os.environ.get("SPINNING_TOP_BINARY_DIR")
    if not path or not (pathlib.Path(path) / "cmake_install.cmake").is_file():
        pytest.fail("SPINNING_TOP_BINARY_DIR must name spinning_top's build folder (with its cmake_install.cmake)")
    return pathlib.Path(path).resolve()


def configured_prefix(binary_dir):
    """The CMAKE_INSTALL_PREFIX the package was configured with (cmake_install.cmake's default)."""
    match = re.search(r'set\(CMAKE_INSTALL_PREFIX "([^"]*)"\)', (binary_dir / "cmake_install.cmake").read_text())
    assert match, "no CMAKE_INSTALL_PREFIX in cmake_install.cmake"
    return match.group(1)


def stage_install(binary_dir, stage):
    """`make install` of the package into stage + its prefix (DESTDIR); returns that prefix.

    catkin writes the prefix into the installed package configuration (the folders it searches
    for the libraries): those are made to name the staged prefix, as an install there would."""
    prefix = configured_prefix(binary_dir)
    run(["cmake", "-P", str(binary_dir / "cmake_install.cmake")], env={**os.environ, "DESTDIR": str(stage)})
    staged = pathlib.Path(str(stage) + prefix)
    config_dir = staged / "share/spinning_top/cmake"
    assert (config_dir / "spinning_topConfig.cmake").is_file(), sorted(str(p) for p in staged.rglob("*Config.cmake"))
    # Only the prefix itself and the folders under it, not other paths that begin with its text
    # (/usr/include/eigen3 where the prefix is /usr).
    pattern = re.compile(re.escape(prefix) + r"(?=/lib\b|/include\b|/share\b|[\";) ]|$)", re.M)
    for config in config_dir.glob("*.cmake"):
        config.write_text(pattern.sub(str(staged), config.read_text()))
    return staged


def test_a_downstream_package_builds_against_the_install_space_under_gcc_9s_default(binary_dir, tmp_path):
    staged = stage_install(binary_dir, tmp_path / "stage")
    assert (staged / "include/spinning_top/simulator.hpp").is_file()
    assert list((staged / "lib").glob("libspinning_top_core.*"))

    # The environment's prefixes (ROS's), without spinning_top's devel space: only the install
    # space may provide it.
    devel = os.environ.get("SPINNING_TOP_DEVEL", "")
    others = [p for p in os.environ.get("CMAKE_PREFIX_PATH", "").split(os.pathsep)
              if p and not (devel and os.path.realpath(p) == os.path.realpath(devel))]
    # Nor make's settings of a `make run_tests` this runs under (its -s would hide the compile line).
    env = {k: v for k, v in os.environ.items()
           if k not in ("CMAKE_PREFIX_PATH", "ROS_PACKAGE_PATH", "MAKEFLAGS", "MFLAGS", "MAKELEVEL", "MAKEOVERRIDES")}
    build = tmp_path / "build"
    run(["cmake", "-S", str(HERE), "-B", str(build),
         "-DCMAKE_PREFIX_PATH=" + ";".join([str(staged)] + others),
         "-DCMAKE_CXX_FLAGS=-std=gnu++14",  # GCC 9's default
         "-DCATKIN_DEVEL_PREFIX=" + str(tmp_path / "devel"),
         "-DPYTHON_EXECUTABLE=/usr/bin/python3", "-DCATKIN_ENABLE_TESTING=OFF"], env=env)
    cache = (build / "CMakeCache.txt").read_text()
    found = re.search(r"^spinning_top_DIR:PATH=(.*)$", cache, re.M)
    assert found and pathlib.Path(found.group(1)).resolve() == (staged / "share/spinning_top/cmake").resolve(), \
        found and found.group(1)

    built = run(["cmake", "--build", str(build), "--", "VERBOSE=1"], env=env)
    compile_line = next((line for line in built.stdout.splitlines() if "downstream.cpp" in line and " -c " in line),
                        None)
    assert compile_line, built.stdout[-4000:]
    # GCC 9's default is there, and the exported requirement after it (the last -std wins).
    assert compile_line.index("-std=gnu++14") < compile_line.rindex("++17"), compile_line

    program = tmp_path / "devel/lib/spinning_top_downstream/spinning_top_downstream"
    if not program.exists():
        program = next(build.rglob("spinning_top_downstream"))
    ran = run([str(program)], env={**env, "LD_LIBRARY_PATH": str(staged / "lib")})
    assert ran.stdout.startswith("downstream: C++ 201703, t = 0.01 s, auto: "), ran.stdout
