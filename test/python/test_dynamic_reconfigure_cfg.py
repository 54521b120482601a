"""cfg/SpinningTop.cfg, dynamic_reconfigure's generator script, writes none of its defaults: they
are the configuration's (include/spinning_top/defaults.def, issue 17), the same doubles as the
key table's. The script is run here with a generator that records its parameters."""
import runpy
import sys
import types

import pytest

import spinning_top as st


@pytest.fixture
def cfg_parameters(source_dir, monkeypatch):
    """(name, level, description, default) of each parameter the cfg adds."""
    added = []

    class ParameterGenerator:
        def add(self, name, paramtype, level, description, default=None, *args, **kwargs):
            added.append((name, level, description, default))

        def generate(self, *args):
            return 0

    generator = types.ModuleType("dynamic_reconfigure.parameter_generator_catkin")
    generator.ParameterGenerator, generator.double_t = ParameterGenerator, "double"
    monkeypatch.setitem(sys.modules, "dynamic_reconfigure", types.ModuleType("dynamic_reconfigure"))
    monkeypatch.setitem(sys.modules, "dynamic_reconfigure.parameter_generator_catkin", generator)
    with pytest.raises(SystemExit) as exit_code:
        runpy.run_path(str(source_dir / "cfg" / "SpinningTop.cfg"), run_name="__main__")
    assert exit_code.value.code == 0
    return added


def test_cfg_defaults_are_the_key_tables(cfg_parameters):
    specs = {spec["key"]: spec for spec in st.parameter_specs()}
    compared = 0
    for name, _, _, default in cfg_parameters:
        # The live spin is the scene's initial/spin; rate and real_time_factor are the node's own
        # (NodeSettings, from the same defaults.def) and have no key in the table.
        key = name if name in specs else f"initial/{name}"
        if key not in specs:
            assert name in ("rate", "real_time_factor"), name
            continue
        assert type(default) is float and default == float(specs[key]["default"]), name
        compared += 1
    assert compared == 11  # k, g, e, restitution_speed, m, A, C, h, spin, tolerance, step
