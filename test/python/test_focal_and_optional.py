"""The Python without what rosdep cannot install or Ubuntu 20.04 (Noetic) does not ship (issue 20,
items 5 and 6): Dask is optional (no rosdep key), pandas 0.25 has no DataFrame.attrs, SciPy 1.3
no scipy.stats.qmc. Each is taken away here as it is missing there: a local sweep and a map work
without them, and what needs them is refused in one line that says what to install."""
import ast
import pathlib
import subprocess
import sys

import pandas as pd
import pytest
import scipy
import scipy.stats

from spinning_top import stability_map, sweep

PACKAGE_DIR = pathlib.Path(sweep.__file__).resolve().parent
GRID = ["--vary", "initial/spin=100:150:2", "--vary", "initial/tilt=0.1:0.2:2", "--duration", "0.05"]


def _main(capsys, *argv, config):
    status = sweep.main(["--config", str(config), "--no-progress", *argv])
    out, err = capsys.readouterr()
    return status, out, err.strip().splitlines()


# --- Dask (item 5) -----------------------------------------------------------------------------

def test_a_local_sweep_imports_no_dask_and_no_qmc(source_dir, tmp_path):
    # A fresh interpreter where dask, distributed and scipy.stats.qmc cannot be imported (as on a
    # machine that installed the rosdep keys only, with focal's SciPy): importing the package and
    # a local grid sweep with its map work.
    script = f"""
import sys
for name in ("dask", "distributed", "scipy.stats.qmc"):
    sys.modules[name] = None
from spinning_top import plot, stability_map, sweep
status = sweep.main(["--config", {str(source_dir / "config/fixed_tip.yaml")!r}, "--no-progress",
                     "--output", {str(tmp_path / "rows.csv")!r}, "--plot", {str(tmp_path / "map.png")!r}, *{GRID!r}])
loaded = sorted(n for n, m in sys.modules.items() if m is not None and n.split(".")[0] in ("dask", "distributed"))
print("status", status, "loaded", loaded)
"""
    result = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "status 0 loaded []", result.stderr
    assert (tmp_path / "rows.csv").read_text().count("\n") == 5
    assert (tmp_path / "map.png").stat().st_size > 0


@pytest.mark.parametrize("blocked", ["distributed", "dask"])
def test_a_scheduler_without_dask_is_refused_in_one_line_saying_how_to_install_it(
        blocked, monkeypatch, capsys, source_dir, tmp_path):
    monkeypatch.setitem(sys.modules, blocked, None)
    monkeypatch.setitem(sys.modules, "distributed", None)  # distributed needs dask
    status, out, err = _main(capsys, "--scheduler", "tcp://127.0.0.1:8786", "--output", str(tmp_path / "rows.csv"),
                             *GRID, config=source_dir / "config/fixed_tip.yaml")
    assert status == 2
    assert out == ""
    assert len(err) == 1, err
    assert err[0].startswith("sweep: error: --scheduler: a Dask scheduler needs Dask, which is not installed here")
    assert "apt-get install python3-dask python3-distributed" in err[0]
    assert not (tmp_path / "rows.csv").exists()


def test_sweep_run_with_a_scheduler_and_no_dask_raises_not_available(monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)
    cases = sweep.design({"initial/spin": (100, 150, 2)})
    with pytest.raises(sweep.NotAvailable, match="apt-get install python3-dask python3-distributed"):
        sweep.run({"scene": "fixed_tip"}, cases, duration=0.05, scheduler="tcp://127.0.0.1:8786")
    assert issubclass(sweep.NotAvailable, ImportError)


# --- SciPy without qmc (item 6) ------------------------------------------------------------------

@pytest.fixture
def scipy_1_3(monkeypatch):
    """scipy.stats as SciPy 1.3.3 (Ubuntu 20.04) has it: without qmc."""
    monkeypatch.setitem(sys.modules, "scipy.stats.qmc", None)
    monkeypatch.delattr(scipy.stats, "qmc", raising=False)
    monkeypatch.setattr(scipy, "__version__", "1.3.3")


def test_a_sobol_design_without_qmc_says_it_needs_scipy_1_7(scipy_1_3):
    with pytest.raises(sweep.NotAvailable) as refused:
        sweep.design({"initial/spin": (0, 200)}, "sobol", 8)
    assert str(refused.value) == ("a sobol design needs scipy.stats.qmc (SciPy >= 1.7) and SciPy 1.3.3 is installed: "
                                  "use a random design, or a newer SciPy (pip3 install --user 'scipy>=1.7')")
    # The other designs do not need it.
    assert len(sweep.design({"initial/spin": (0, 200)}, "random", 8)["initial/spin"]) == 8
    assert len(sweep.design({"initial/spin": (0, 200, 3)})["initial/spin"]) == 3


def test_sweep_design_sobol_without_qmc_is_refused_before_running(scipy_1_3, capsys, source_dir):
    status, out, err = _main(capsys, "--vary", "initial/spin=0:200", "--design", "sobol", "--cases", "8",
                             config=source_dir / "config/fixed_tip.yaml")
    assert (status, out) == (2, "")
    assert err == ["sweep: error: --design: a sobol design needs scipy.stats.qmc (SciPy >= 1.7) and SciPy 1.3.3 is "
                   "installed: use a random design, or a newer SciPy (pip3 install --user 'scipy>=1.7')"]


# --- pandas without DataFrame.attrs (item 6) -----------------------------------------------------

class _Pandas025Attrs:
    """DataFrame.attrs as the package's code finds it under pandas 0.25: missing (AttributeError,
    for the class and its instances). pandas' own code still finds its attrs and keeps working."""

    def __init__(self, real):
        self.real = real

    def __get__(self, frame, owner=None):
        caller = sys._getframe(1).f_globals.get("__name__", "")
        if caller.split(".")[0] == "spinning_top":
            raise AttributeError("type object 'DataFrame' has no attribute 'attrs' (pandas 0.25.3)")
        return self.real.__get__(frame, owner)

    def __set__(self, frame, value):
        self.real.__set__(frame, value)


@pytest.fixture
def pandas_0_25(monkeypatch):
    monkeypatch.setattr(pd.DataFrame, "attrs", _Pandas025Attrs(pd.core.generic.NDFrame.attrs), raising=False)


def test_rows_keep_their_base_where_pandas_has_attrs():
    base = {"scene": "frictionless"}
    rows = sweep.run(base, sweep.design({"initial/spin": (100, 150, 2)}), duration=0.05)
    assert sweep.sweep_info(rows) == (base, 0.05)


def test_sweeps_and_maps_need_no_dataframe_attrs(pandas_0_25, monkeypatch, capsys, source_dir, tmp_path):
    base = {"scene": "fixed_tip"}
    rows = sweep.run(base, sweep.design({"initial/spin": (100, 150, 2), "initial/tilt": (0.1, 0.2, 2)}), duration=0.05)
    assert len(rows) == 4
    assert sweep.sweep_info(rows) == (None, None)
    thresholds = []
    real_threshold = stability_map.sleeping_threshold
    monkeypatch.setattr(stability_map, "sleeping_threshold", lambda b: thresholds.append(dict(b)) or real_threshold(b))
    # Without the base the threshold is not guessed; given it, it is drawn.
    stability_map.plot(rows, "initial/spin", "initial/tilt", tmp_path / "unknown.png")
    assert thresholds == []
    stability_map.plot(rows, "initial/spin", "initial/tilt", tmp_path / "known.png", base=base, duration=0.05)
    assert thresholds == [base]
    # The command line passes its base: the same map as with pandas >= 1.0.
    status, _, err = _main(capsys, "--output", str(tmp_path / "rows.csv"), "--plot", str(tmp_path / "map.png"),
                           *GRID, config=source_dir / "config/fixed_tip.yaml")
    assert status == 0, err
    assert len(thresholds) == 2 and thresholds[1]["scene"] == "fixed_tip" and "mass" in thresholds[1]
    assert (tmp_path / "map.png").stat().st_size > 0


# --- where the newer APIs are used -----------------------------------------------------------------

class _Uses(ast.NodeVisitor):
    """(innermost function or "<module>", line) of each use of a name: an attribute, or a part of
    an imported module's name or an imported name."""

    def __init__(self, name):
        self.name, self.where, self.found = name, ["<module>"], []

    def visit_FunctionDef(self, node):
        self.where.append(node.name)
        self.generic_visit(node)
        self.where.pop()

    def _check(self, node, names):
        if self.name in names:
            self.found.append((self.where[-1], node.lineno))

    def visit_Attribute(self, node):
        self._check(node, [node.attr])
        self.generic_visit(node)

    def visit_Import(self, node):
        self._check(node, [part for a in node.names for part in a.name.split(".")])

    def visit_ImportFrom(self, node):
        self._check(node, [a.name for a in node.names] + (node.module or "").split("."))


@pytest.mark.parametrize("name, allowed", [
    ("attrs", {"set_sweep_info", "sweep_info"}),  # DataFrame.attrs: pandas >= 1.0
    ("qmc", {"_sobol_engine", "design"}),         # scipy.stats.qmc: SciPy >= 1.7
    # Dask: optional; _client and _run use it once _distributed() found it.
    ("distributed", {"_distributed", "_client", "_run"}),
    ("dask", set()),
])
def test_newer_and_optional_apis_are_used_only_behind_their_checks(name, allowed):
    # No use at import time (a missing module would break `import spinning_top`), and only in
    # the functions that check for it or run after the check.
    for path in sorted(PACKAGE_DIR.glob("*.py")):
        finder = _Uses(name)
        finder.visit(ast.parse(path.read_text(), str(path)))
        assert {where for where, _ in finder.found} <= allowed, (path.name, finder.found)
