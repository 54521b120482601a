"""spinning_top: the symmetric spinning top's core from Python (issue 11).

The physics is the C++ core's (``_core``, pybind11); this package adds nothing to it but
conveniences and the parameter sweep::

    import spinning_top as st
    sim = st.Simulator({"scene": "fixed_tip", "initial/tilt": 0.3, "initial/spin": 150})
    sim.integrator_description()        # 'auto: exact: closed form, ...'
    traj = sim.run(np.linspace(0, 10, 1001))   # dict of numpy arrays, as `simulate` writes them
    traj["phase"], traj["events"]       # per row: contact | flight | skim; "" or the transition
    st.run_case({"scene": "fixed_tip", "initial/spin": 0.0, "initial/tilt": 0.3})

After a lift-off the top flies, lands and hops (doc/spec/HYBRID.md; ``after_lift_off: stop``
ends the run there instead). ``Simulator.run`` has a row at each time asked for and one at each
transition (lift_off, take_off, landing) at its own time, named in ``events``; ``tip_height`` is
the tip's height above the floor (0 in contact). ``run_case`` counts the hops (``lift_offs``,
``landings``, ``first_lift_off_time``, ``max_hop_height``).

Keys are those of the scene files and of the node's parameters (``parameter_specs()``), values
numbers or text; every configuration is validated by the core, so a bad one raises
``InvalidParameter`` with the core's message and the key in ``.key``.
"""
from pkgutil import extend_path

# The compiled _core lives in the build's devel space, the .py files in the source tree; a
# process that finds the source first (a Dask worker spawned with the parent's sys.path) must
# still find _core on the rest of sys.path, as catkin's devel-space __init__.py does.
__path__ = extend_path(__path__, __name__)

from spinning_top._core import (  # noqa: F401  (the public API)
    CaseSettings,
    InvalidParameter,
    SceneFileError,
    Simulator,
    StepBudgetExceeded,
    parameter_specs,
    read_scene_file,
    run_cases,
    validate,
)


def load_scene(path, overrides=None):
    """The keys of a scene file (YAML, read by the core's reader) with `overrides` applied."""
    keys = dict(read_scene_file(str(path)))
    keys.update(overrides or {})
    return keys


def simulator_from_file(path, overrides=None):
    """A Simulator from a scene file, which must give every required key (as `simulate --config`)."""
    return Simulator(load_scene(path, overrides), require_all=True)


_DEFAULT_SETTINGS = CaseSettings()  # the core's


def run_case(keys, duration=_DEFAULT_SETTINGS.duration, sample_rate=_DEFAULT_SETTINGS.sample_rate,
             max_steps=_DEFAULT_SETTINGS.max_steps):
    """Runs one configuration to `duration` or its first event; returns the row as a dict.

    outcome is 'none' (ran to the end; hops do not end a run), the terminal event ('lift_off'
    where the run cannot fly on, 'fallen', 'energy_drift', 'non_finite') or 'out_of_steps'; the
    hops are in lift_offs, landings, first_lift_off_time (nan: none) and max_hop_height.
    sweep.OUTCOME_COLUMNS describes every column. A configuration the core refuses raises
    InvalidParameter.
    """
    validate(keys)
    row = run_cases(keys, {}, CaseSettings(duration, sample_rate, max_steps))
    return {name: (column[0] if len(column) else None) for name, column in row.items()}
