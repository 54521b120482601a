"""Issue 19 through the Python front end and the sweep: the core's reader and validation refuse
what the attack found, and a scene file means the same to the node's rosparam (YAML 1.1, PyYAML
with rosparam's resolvers) as to the core (YAML 1.2, yaml-cpp)."""
import subprocess
import sys

import numpy as np
import pytest
import yaml

import spinning_top as st

try:  # rosparam's loader: PyYAML plus its deg()/rad() resolvers, as the node's launch file reads
    import rosparam  # noqa: F401
except ImportError:  # pragma: no cover - without ROS, PyYAML's own resolver is YAML 1.1 still
    pass

SCENE = ("scene: fixed_tip\nmass: 0.1\ninertia_transverse: 4.0e-5\ninertia_axial: 6.0e-5\ntip_distance: 0.02\n"
         "initial:\n  tilt: 0.3\n  spin: 150.0\n")

# Plain scalars in many forms: the core takes one only where PyYAML reads the same number.
FORMS = ["9.8", "10", "-3", "+2.5", "0", "-0", "-0.0", ".5", "1.", "4.0e-5", "1.0e+7", "1.5E+3", "2147483647",
         "010.5", "0.000001", "010", "08", "0o10", "0x10", "0b11", "1_000", "1:20", "1:20.5", "1e1", "1.0e1", "5e-5",
         "1E+5", "-.5", "+.5", ".5e+1", "yes", "no", "on", "off", "true", "y", "n", ".inf", "-.inf", ".nan", "inf",
         "nan", "NaN", "deg(30)", "rad(0.3)", "2147483648", "-2147483649", "1e400", "1.0e+400", "9.8 m/s", "1,5",
         "2001-01-01", "=", "~", "null", "0x1p3", "00.25", "1.0e-400"]


def pyyaml_number(text):
    """What the node gets from rosparam for `gravity: text`: a number, or None for anything else."""
    value = yaml.safe_load("gravity: " + text)["gravity"]
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    if isinstance(value, int) and abs(value) > 2**31 - 1:
        return None  # rosparam cannot send it (XML-RPC int)
    return float(value)


@pytest.mark.parametrize("text", FORMS)
def test_a_number_the_core_reads_is_the_number_rosparam_reads(tmp_path, text):
    path = tmp_path / "scene.yaml"
    path.write_text(SCENE + "gravity: " + text + "\n")
    try:
        keys = st.read_scene_file(str(path))
        st.validate(keys, require_all=True)
    except (st.SceneFileError, st.InvalidParameter) as refused:
        assert str(refused).startswith("gravity: "), str(refused)
        return
    assert keys["gravity"] == text
    expected = pyyaml_number(text)
    assert expected is not None, f"{text!r} is no number to rosparam, but the core took it"
    assert float(text) == expected


@pytest.mark.parametrize("line", ['gravity: "9.8"', "mass: '0.1'", "mass: !!str 0.1", "gravity: !foo 9.8"])
def test_quoted_and_tagged_numbers_are_refused(tmp_path, line):
    path = tmp_path / "scene.yaml"
    path.write_text(SCENE.replace("mass: 0.1\n", "") + line + "\n")
    with pytest.raises(st.SceneFileError, match=line.split(":")[0] + ": "):
        st.read_scene_file(str(path))


def test_unbounded_files_and_alias_bombs_are_refused(tmp_path):
    for device in ("/dev/zero", "/dev/urandom"):
        with pytest.raises(st.SceneFileError, match="is a character device"):
            st.read_scene_file(device)
    bomb = tmp_path / "bomb.yaml"
    lines = ["a0: &a0 {x: 1, y: 1}"] + [f"a{i}: &a{i} {{x: *a{i - 1}, y: *a{i - 1}}}" for i in range(1, 30)]
    bomb.write_text("\n".join(lines) + "\n")
    with pytest.raises(st.SceneFileError, match="anchor"):
        st.read_scene_file(str(bomb))


def test_the_sweep_refuses_a_device_as_its_scene_file(tmp_path):
    # Before: a MemoryError traceback after reading /dev/zero.
    result = subprocess.run([sys.executable, "-m", "spinning_top.sweep", "--config", "/dev/zero",
                             "--vary", "initial/spin=100:200:3", "--output", str(tmp_path / "rows.csv")],
                            capture_output=True, text=True, timeout=120)
    assert result.returncode != 0
    assert "is a character device" in result.stderr
    assert "Traceback" not in result.stderr


def test_initial_velocity_is_bounded_in_every_python_path():
    keys = {"scene": "viscous", "friction": 0.5, "initial/velocity_x": 1e300}
    for call in (lambda: st.Simulator(keys), lambda: st.run_case(keys), lambda: st.validate(keys)):
        with pytest.raises(st.InvalidParameter) as refused:
            call()
        assert refused.value.key == "initial/velocity_x"
    rows = st.run_cases({"scene": "viscous", "friction": 0.5}, {"initial/velocity_x": np.array([0.1, 1e300])},
                        st.CaseSettings(0.1))
    assert list(rows["outcome"]) == ["none", "refused"]
    assert np.isfinite(rows["final_energy"][0])


def test_advance_to_an_earlier_time_raises():
    sim = st.Simulator({"scene": "fixed_tip"})
    sim.advance_to(1.0)
    with pytest.raises(ValueError, match="before the simulator's time 1 s"):
        sim.advance_to(0.5)
    for bad in (float("nan"), float("inf")):
        with pytest.raises(ValueError, match="finite"):
            sim.advance_to(bad)
    assert sim.time == 1.0
    sim.advance_to(1.0)  # the same time: nothing to do, no error
    with pytest.raises(ValueError, match="finite"):
        sim.run([1.0, float("inf")])


def test_case_settings_blame_the_culprit_with_short_numbers():
    with pytest.raises(st.InvalidParameter) as refused:
        st.CaseSettings(1e300)
    assert refused.value.key == "duration"
    assert "1e+300" in str(refused.value) and len(str(refused.value)) < 120
    with pytest.raises(st.InvalidParameter) as refused:
        st.CaseSettings(10.0, 1e300)
    assert refused.value.key == "sample_rate"


def test_times_beyond_1e9_s_and_malformed_arguments_are_refused_naming_them():
    # Found by the attack harness: run(np.linspace(0, 1e300, 3)) gave NaN quaternions without an
    # event (exact: E = 2e231 at 1e17 s). The longest simulated time is 1e9 s.
    sim = st.Simulator({"scene": "frictionless"})
    with pytest.raises(ValueError, match="^times: at most 1e9 s"):
        sim.run(np.linspace(0, 1e300, 3))
    with pytest.raises(ValueError, match="t must be at most 1e9 s"):
        sim.advance_to(1e20)
    with pytest.raises(st.InvalidParameter) as refused:
        st.CaseSettings(2e9, 1e-3)
    assert refused.value.key == "duration"
    with pytest.raises(ValueError, match="^times: must be one-dimensional"):
        sim.run(np.zeros((2, 2)))
    with pytest.raises(st.InvalidParameter) as refused:
        st.validate({"scene": "fixed_tip", "step": np.array([0.1, 0.2])})
    assert refused.value.key == "step"
    with pytest.raises(ValueError, match="^initial/spin: must be numbers"):
        st.run_cases({"scene": "fixed_tip"}, {"initial/spin": ["a"]}, st.CaseSettings(0.1))
    with pytest.raises(ValueError, match="^initial/spin: no values"):
        st.run_cases({"scene": "fixed_tip"}, {"initial/spin": []}, st.CaseSettings(0.1))
    assert sim.time == 0.0
