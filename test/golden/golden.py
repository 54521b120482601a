#!/usr/bin/env python3
"""Golden outputs: the core's results, bit for bit, as a reference build produced them.

A refactoring of the integration layer must not change one bit of any output (issue 17, "One
integration layer"). This tool runs a fixed matrix of cases through the batch simulator
`simulate` (every scene x every integrator, the shipped and extreme scene files, two output rates,
events, step budgets) and through the Python module's `run_cases` (the sweep's rows), and
records a SHA-256 of each output with the exit code. `check` runs the same matrix on another
build and compares.

    golden.py generate SIMULATE > test/golden/outputs.txt   # from the reference build
    golden.py check SIMULATE [test/golden/outputs.txt]      # 0 if every output is identical
    golden.py show SIMULATE NAME                             # one case's command and output

The Python cases need the build's devel space on the path (`source build/devel/setup.bash`).
The hashes hold for one compiler and platform (x86-64, SSE2 arithmetic, the build flags of
CMakeLists.txt); a different compiler may round differently and needs a new reference.
"""
import hashlib
import os
import pathlib
import subprocess
import sys

SOURCE_DIR = pathlib.Path(__file__).resolve().parents[2]
MANIFEST = pathlib.Path(__file__).resolve().parent / "outputs.txt"

SCENES = ("fixed_tip", "frictionless", "viscous")
INTEGRATORS = ("auto", "rk4", "dopri5", "dop853", "splitting4", "splitting6", "splitting8", "gauss6", "radau5",
               "radau9", "rodas4", "exact")
# 1 kHz (the node's tick: one row per default step) and 30 Hz (1/30 s is not a double: requests
# fall between steps and substep plans are uneven).
RATES = ("1000", "30")


def simulate_cases():
    """(name, arguments of simulate) for every case."""
    cases = []
    for scene in SCENES:
        config = f"config/{scene}.yaml"
        for integrator in INTEGRATORS:
            for rate in RATES:
                cases.append((f"{scene}/{integrator}/{rate}Hz",
                              ["--config", config, "--set", f"integrator={integrator}", "--duration", "2",
                               "--output-rate", rate]))
        # The default over 10 s, as a user runs it.
        cases.append((f"{scene}/default/10s", ["--config", config, "--duration", "10", "--output-rate", "100"]))
        # Step budgets: the rows up to where the run stopped (exit 3).
        for integrator in ("rk4", "dop853", "radau5", "auto"):
            cases.append((f"{scene}/{integrator}/max_steps", ["--config", config, "--set", f"integrator={integrator}",
                                                              "--duration", "1", "--max-steps", "40"]))
    for path in sorted((SOURCE_DIR / "config" / "extreme").glob("*.yaml")):
        for rate in RATES:
            cases.append((f"extreme/{path.stem}/{rate}Hz", ["--config", f"config/extreme/{path.stem}.yaml",
                                                            "--duration", "2", "--output-rate", rate]))
    # Events and states that take other branches of the methods.
    events = {
        # The axis reaches the floor (fallen) in every scene; exact's closed-form event and the
        # steppers' located one.
        "fallen/fixed_tip/exact": ["--config", "config/fixed_tip.yaml", "--set", "initial/spin=0"],
        "fallen/fixed_tip/dop853": ["--config", "config/fixed_tip.yaml", "--set", "initial/spin=0",
                                    "--set", "integrator=dop853"],
        "fallen/fixed_tip/rk4": ["--config", "config/fixed_tip.yaml", "--set", "initial/spin=0",
                                 "--set", "integrator=rk4"],
        "fallen/frictionless/exact": ["--config", "config/frictionless.yaml", "--set", "initial/spin=5"],
        "fallen/viscous/auto": ["--config", "config/viscous.yaml", "--set", "initial/spin=5"],
        "fallen/viscous/radau5": ["--config", "config/viscous.yaml", "--set", "initial/spin=5",
                                  "--set", "integrator=radau5"],
        # Lift-off: R reaches 0.
        "lift_off/fixed_tip/dop853": ["--config", "config/extreme/lift_off.yaml", "--set", "integrator=dop853"],
        "lift_off/fixed_tip/splitting6": ["--config", "config/extreme/lift_off.yaml", "--set", "integrator=splitting6",
                                          "--set", "step=1e-4"],
        "lift_off/frictionless/exact": ["--config", "config/frictionless.yaml", "--set", "initial/precession_rate=60",
                                        "--set", "initial/tilt=0.8"],
        "lift_off/viscous/auto": ["--config", "config/viscous.yaml", "--set", "initial/precession_rate=60",
                                  "--set", "initial/tilt=0.8"],
        "lift_off/viscous/stiff": ["--config", "config/viscous.yaml", "--set", "initial/precession_rate=60",
                                   "--set", "initial/tilt=0.8", "--set", "friction=2000"],
        # Issue 18: hops with bounces, a fixed tip that flies and lands on a new pivot, and the
        # contact model alone (after_lift_off: stop).
        "hops/frictionless/bounce": ["--config", "config/frictionless.yaml", "--set", "initial/precession_rate=60",
                                     "--set", "initial/tilt=0.8", "--set", "restitution=0.5",
                                     "--set", "restitution_speed=0"],
        "hops/fixed_tip/nutation": ["--config", "config/fixed_tip.yaml", "--set", "initial/nutation_rate=20"],
        "hops/frictionless/stop": ["--config", "config/frictionless.yaml", "--set", "initial/precession_rate=60",
                                   "--set", "initial/tilt=0.8", "--set", "after_lift_off=stop"],
        # An invalid state at release: one row with its event.
        "lift_off/at_release": ["--config", "config/fixed_tip.yaml", "--set", "initial/nutation_rate=200"],
        # A state exact refuses (nothing drives the nutation): auto runs its fallback, dop853, and
        # says why on the first line.
        "fallback/frictionless/weightless_at_rest": ["--config", "config/frictionless.yaml", "--set", "gravity=0",
                                                     "--set", "initial/spin=0"],
        # The axis vertical while it moves: exact through the pole of its Euler angles.
        "vertical_moving/fixed_tip": ["--config", "config/fixed_tip.yaml", "--set", "initial/tilt=0",
                               "--set", "initial/nutation_rate=1"],
        # A tolerance too loose for stiff friction: the energy guard ends the run.
        "energy_drift/viscous/dop853": ["--config", "config/viscous.yaml", "--set", "integrator=dop853",
                                        "--set", "tolerance=9e-3", "--set", "friction=50"],
        "energy_drift/viscous/dopri5": ["--config", "config/viscous.yaml", "--set", "integrator=dopri5",
                                        "--set", "tolerance=1e-2", "--set", "friction=50"],
        # Stiff friction with an initial slip, and a sliding start.
        "slip/viscous/auto": ["--config", "config/viscous.yaml", "--set", "friction=1e4",
                              "--set", "initial/velocity_x=0.3"],
        "slip/viscous/rodas4": ["--config", "config/viscous.yaml", "--set", "friction=100",
                                "--set", "initial/velocity_y=0.2", "--set", "integrator=rodas4"],
        # Torque-free, sleeping and without gravity: exact's other closed forms.
        "no_gravity/frictionless/exact": ["--config", "config/frictionless.yaml", "--set", "gravity=0",
                                          "--set", "initial/precession_rate=3"],
        "fast_spin/fixed_tip/exact": ["--config", "config/fixed_tip.yaml", "--set", "initial/spin=2000",
                                      "--set", "initial/nutation_rate=3"],
    }
    for name, arguments in sorted(events.items()):
        for rate in RATES:
            cases.append((f"{name}/{rate}Hz", arguments + ["--duration", "3", "--output-rate", rate]))
    return cases


def python_cases():
    """(name, base keys, varied keys) for run_cases: the sweep's rows (closed-form extremes for
    exact, sampled ones for time-steppers)."""
    import numpy as np

    spins = np.linspace(0.0, 200.0, 5)
    tilts = np.linspace(0.1, 1.3, 4)
    grid = {"initial/spin": np.repeat(spins, len(tilts)), "initial/tilt": np.tile(tilts, len(spins))}
    return [
        ("sweep/fixed_tip", {"scene": "fixed_tip"}, grid),
        ("sweep/frictionless", {"scene": "frictionless"}, grid),
        ("sweep/viscous", {"scene": "viscous", "friction": "0.05"}, grid),
        ("sweep/fixed_tip/rk4", {"scene": "fixed_tip", "integrator": "rk4"}, grid),
    ]


def run_simulate(simulate, arguments):
    result = subprocess.run([simulate, *arguments, "--output", "-"], cwd=SOURCE_DIR, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, timeout=600)
    return result.returncode, result.stdout


def run_python(base, varied):
    import numpy as np
    import spinning_top as st

    columns = st.run_cases(base, varied, st.CaseSettings(2.0, 1000.0, 1e8))
    # repr() of a float is the shortest text that reads back to the same double: bit for bit.
    text = "".join(f"{key}={[repr(v) for v in list(values)]}\n" for key, values in sorted(columns.items()))
    # Simulator.run: the module's own sampling of one run.
    simulator = st.Simulator({**base, "initial/spin": "150"})
    result = simulator.run(np.linspace(0.0, 1.0, 301))
    text += "".join(f"{key}={[repr(v) for v in np.ravel(values).tolist()]}\n" for key, values in sorted(result.items()))
    return 0, text.encode()


def outputs(simulate, with_python=True):
    """Yields (name, exit code, sha256 of the output) for every case."""
    for name, arguments in simulate_cases():
        code, data = run_simulate(simulate, arguments)
        yield name, code, hashlib.sha256(data).hexdigest()
    if with_python:
        for name, base, varied in python_cases():
            code, data = run_python(base, varied)
            yield name, code, hashlib.sha256(data).hexdigest()


def read_manifest(path):
    expected = {}
    for line in pathlib.Path(path).read_text().splitlines():
        if not line or line.startswith("#"):
            continue
        name, code, digest = line.split()
        expected[name] = (int(code), digest)
    return expected


def main(argv):
    if len(argv) < 3 or argv[1] not in ("generate", "check", "show"):
        print(__doc__, file=sys.stderr)
        return 2
    command, simulate = argv[1], os.path.abspath(argv[2])
    if command == "generate":
        print("# name exit_code sha256(output): golden outputs of test/golden/golden.py (issue 17)")
        for name, code, digest in outputs(simulate):
            print(name, code, digest, flush=True)
        return 0
    if command == "show":
        for name, arguments in simulate_cases():
            if name == argv[3]:
                print("simulate " + " ".join(arguments), file=sys.stderr)
                code, data = run_simulate(simulate, arguments)
                sys.stdout.buffer.write(data)
                return code
        print(f"no case {argv[3]}", file=sys.stderr)
        return 2
    expected = read_manifest(argv[3] if len(argv) > 3 else MANIFEST)
    differing, seen = [], set()
    for name, code, digest in outputs(simulate):
        seen.add(name)
        if expected.get(name) != (code, digest):
            differing.append(name)
            print(f"differs: {name} (exit {code}, expected {expected.get(name, ('missing', ''))[0]})")
    missing = sorted(set(expected) - seen)
    for name in missing:
        print(f"not run: {name}")
    print(f"{len(seen) - len(differing)} identical, {len(differing)} differing, {len(missing)} not run")
    return 1 if differing or missing else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
