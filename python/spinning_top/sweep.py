"""Parameter sweeps: many cases of one scene, each run by the C++ core to a duration or to its
first terminal event (a hop goes on: issue 18), one row per case (issue 11).

    import spinning_top as st
    from spinning_top import sweep
    base = st.load_scene("config/fixed_tip.yaml")
    cases = sweep.design({"initial/spin": (0, 200, 101), "initial/tilt": (0, 1.4, 71)})
    rows = sweep.run(base, cases)                      # all local cores
    rows = sweep.run(base, cases, scheduler="tcp://host:8786")   # a Dask cluster (optional)

A design is a dict key -> numpy array (one value per case). The rows are a pandas DataFrame:
the varied keys, then the outcome columns of ``OUTCOME_COLUMNS``. Cases are run in batches by
``_core.run_cases`` without the GIL, on a thread pool (local) or as Dask tasks (cluster); each
case depends on its own configuration only, so the rows are the same, bit for bit, whichever
runs them and however they are batched.

Dask is optional (python3-dask and python3-distributed have no rosdep rule): it is imported only
for a scheduler, and a local sweep never needs it. The Sobol design needs scipy.stats.qmc (SciPy
>= 1.7), which Ubuntu 20.04 does not ship; it is imported only for that design. Without them, a
sweep that asks for them is refused with NotAvailable, saying what to install.

Command line: ``python3 -m spinning_top.sweep --help``.
"""
import concurrent.futures
import io
import math
import numbers
import os
import socket
import sys
import tempfile
import warnings

import numpy as np

from spinning_top import _cli, _core

#: The columns each case adds to its row, after the varied keys: name -> what it holds (the unit
#: first), in order. The core's run_cases writes them (its one list of them).
OUTCOME_COLUMNS = dict(_core.outcome_columns())

#: A case's settings unless told otherwise: the core's (CaseSettings).
DEFAULT_SETTINGS = _core.CaseSettings()

#: Cases per batch at most: ~0.1 s of fixed-tip work, small against a Dask task's ~1 ms cost.
MAX_BATCH = 4096

#: Cases a sweep may have at most: its rows take ~200 MB; a larger design is refused with its
#: count before anything is allocated (split it, or raise this from Python).
MAX_CASES = 10 ** 6

#: [s] How long reaching a Dask scheduler may take, and how long a sweep waits for a cluster
#: without workers to get one, before they are refused (Dask's own default waits 30 s).
CONNECT_TIMEOUT = 10.0
WORKER_TIMEOUT = 10.0

#: Local threads a sweep may use at most (each is an OS thread).
MAX_WORKERS = 1024

#: Formats of the rows (--output): extension -> name.
ROW_FORMATS = {"csv": "CSV", "parquet": "Parquet"}

#: How to get Dask, for --scheduler (Debian and Ubuntu package it; rosdep does not know it).
DASK_INSTALL = "apt-get install python3-dask python3-distributed (or: pip3 install --user distributed)"


class NotAvailable(ImportError):
    """An optional feature whose module is not installed, or too old, here; the message says
    which and how to get it (Dask for a scheduler, scipy.stats.qmc for a Sobol design)."""


def _distributed():
    """Dask's distributed module, imported only for a scheduler: a local sweep needs no Dask."""
    try:
        import distributed
    except ImportError as error:
        raise NotAvailable(f"a Dask scheduler needs Dask, which is not installed here ({error}); install it with "
                           f"{DASK_INSTALL}, or leave the scheduler out to run on this machine's cores") from None
    return distributed


def _sobol_engine():
    """scipy.stats.qmc (SciPy >= 1.7), imported only for a Sobol design: Ubuntu 20.04 ships
    SciPy 1.3.3, without it, and the grid and random designs do not need it."""
    try:
        from scipy.stats import qmc
    except ImportError:
        try:
            import scipy
            have = f"SciPy {scipy.__version__} is installed"
        except ImportError:
            have = "SciPy is not installed"
        raise NotAvailable(f"a sobol design needs scipy.stats.qmc (SciPy >= 1.7) and {have}: use a random design, "
                           "or a newer SciPy (pip3 install --user 'scipy>=1.7')") from None
    return qmc


def _too_many(count):
    return ValueError(f"{count:.6g} cases, more than the {MAX_CASES:.6g} a sweep may run (sweep.MAX_CASES); "
                      "split the sweep")


def _finite(key, value):
    value = float(value)
    if not math.isfinite(value):
        raise ValueError(f"{key}: {value:.6g} is not a finite number")
    return value


def design(ranges, kind="grid", cases=None, seed=0):
    """The cases of a sweep: key -> array of values.

    ranges: key -> (low, high, n) for a grid axis, (low, high) for a random or Sobol axis, or an
    explicit list of values (grid only). kind: "grid" (every combination, the first key varying
    slowest), "random" (uniform, numpy's PCG64 seeded with `seed`) or "sobol" (scrambled Sobol
    points, scipy.stats.qmc, seeded; NotAvailable where SciPy is older than 1.7); `cases` is the
    number of random or Sobol cases.
    """
    if not ranges:
        raise ValueError("a sweep needs at least one key to vary")
    keys = list(ranges)
    if kind == "grid":
        axes = []
        for key in keys:
            spec = ranges[key]
            if isinstance(spec, tuple) and len(spec) == 3:
                low, high, n = spec
                if not isinstance(n, numbers.Real) or not math.isfinite(n) or int(n) != n or n < 1:
                    raise ValueError(f"{key}: a grid axis needs a whole number of points >= 1, got {n}")
                axes.append((_finite(key, low), _finite(key, high), int(n)))
            elif isinstance(spec, tuple) and len(spec) == 2:
                raise ValueError(f"{key}: a grid axis is (low, high, n) (LOW:HIGH:N) or a list of values; "
                                 "(low, high) is a range of a random or sobol design")
            else:
                values = np.asarray(spec, dtype=float).ravel()
                if values.size == 0:
                    raise ValueError(f"{key}: no values")
                for value in values[~np.isfinite(values)][:1]:
                    _finite(key, value)
                axes.append(values)
        count = math.prod(a[2] if isinstance(a, tuple) else len(a) for a in axes)
        if count > MAX_CASES:  # before any array of that size is asked for
            raise _too_many(count)
        axes = [np.linspace(*a) if isinstance(a, tuple) else a for a in axes]
        mesh = np.meshgrid(*axes, indexing="ij")
        return {key: m.ravel() for key, m in zip(keys, mesh)}
    if kind not in ("random", "sobol"):
        raise ValueError(f"design: kind must be grid, random or sobol, got {kind!r}")
    if not isinstance(cases, numbers.Real) or not math.isfinite(cases) or int(cases) != cases or cases < 1:
        raise ValueError(f"a {kind} design needs cases >= 1, got {cases}")
    if cases > MAX_CASES:
        raise _too_many(cases)
    bounds = []
    for key in keys:
        spec = ranges[key]
        if not (isinstance(spec, tuple) and len(spec) == 2):
            raise ValueError(f"{key}: a {kind} axis is (low, high), got {spec!r}")
        bounds.append((_finite(key, spec[0]), _finite(key, spec[1])))
    if kind == "random":
        unit = np.random.default_rng(seed).random((int(cases), len(keys)))
    else:
        qmc = _sobol_engine()
        sampler = qmc.Sobol(d=len(keys), scramble=True, seed=seed)
        m = math.log2(cases)
        with warnings.catch_warnings():  # the balance of n != 2^m points: the command line says it in one line
            warnings.simplefilter("ignore")
            unit = sampler.random_base2(int(m)) if m == int(m) else sampler.random(int(cases))
    return {key: low + (high - low) * unit[:, i] for i, (key, (low, high)) in enumerate(zip(keys, bounds))}


def run_batch(base, columns, settings):
    """One batch of cases on this process (a Dask task, or a thread of the local pool).
    settings: (duration, sample_rate, max_steps). Module level, so that Dask can send it."""
    return _core.run_cases(base, columns, _core.CaseSettings(*settings))


def _batches(count, workers, batch_size):
    if batch_size is None:
        # Enough batches to keep every worker busy to the end and the progress bar moving.
        batch_size = min(MAX_BATCH, max(1, math.ceil(count / (16 * workers))))
    return [(start, min(count, start + batch_size)) for start in range(0, count, batch_size)]


def _progress_bar(total, enabled):
    if not enabled:
        return None
    try:
        from tqdm import tqdm
    except ImportError:  # python3-tqdm is installed by scripts/setup.sh; the sweep runs without it
        return None
    return tqdm(total=total, unit="case", smoothing=0.1, file=sys.stderr)


def _client(scheduler):
    """(client, whether this call made it): a distributed.Client, or one connected to the address
    within CONNECT_TIMEOUT. ConnectionError (an OSError) naming the address if it cannot be reached;
    NotAvailable if Dask is not installed."""
    Client = _distributed().Client
    if isinstance(scheduler, Client):
        return scheduler, False
    from distributed.comm.addressing import parse_address, parse_host_port

    address = str(scheduler)
    what = _cli.short(address, 60, quote=False)
    try:
        protocol, location = parse_address(address)
        if protocol == "tcp":  # refused or unreachable: known at once, not after Dask's retries
            host, port = parse_host_port(location)
            socket.create_connection((host, port), timeout=CONNECT_TIMEOUT).close()
        return Client(address, timeout=CONNECT_TIMEOUT), True
    except (ValueError, TypeError) as error:
        raise ConnectionError(f"cannot connect to {what}: not a scheduler address ({error})") from None
    except socket.timeout:
        raise ConnectionError(f"cannot connect to {what}: no answer within {CONNECT_TIMEOUT:g} s") from None
    except OSError as error:
        reason = error.strerror or str(error) or type(error).__name__
        raise ConnectionError(f"cannot connect to {what}: {reason}") from None


def _workers(client):
    """The threads of a cluster's workers; waits WORKER_TIMEOUT for a first worker, then refuses
    (its tasks would wait for one forever)."""
    if not client.nthreads():
        try:
            client.wait_for_workers(1, timeout=WORKER_TIMEOUT)
        except (TimeoutError, OSError):
            address = _cli.short(client.scheduler.address, 60, quote=False)
            raise ConnectionError(f"the scheduler at {address} has no workers "
                                  f"(none came within {WORKER_TIMEOUT:g} s)") from None
    return max(1, sum(client.nthreads().values()))


def _whole(name, value, most=None):
    if value is not None and (isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < 1):
        raise ValueError(f"{name}: must be a whole number >= 1, got {value}")
    if value is not None and most is not None and value > most:
        raise ValueError(f"{name}: at most {most}, got {value}")
    return value


def run(base, cases, duration=DEFAULT_SETTINGS.duration, sample_rate=DEFAULT_SETTINGS.sample_rate,
        max_steps=DEFAULT_SETTINGS.max_steps, scheduler=None, workers=None, batch_size=None, progress=False):
    """Runs every case; returns a pandas DataFrame, one row per case in the design's order.

    base: the keys every case shares (e.g. load_scene(...)); cases: design(...). The base with
    each varied key's first value is validated first, so a bad key or base value raises
    InvalidParameter before anything runs; a case the core refuses for its own values (C > 2A
    somewhere in a sweep of C) is a row with outcome "refused" and the core's message.
    scheduler: None for this machine's cores (threads: the core runs without the GIL), or a
    Dask scheduler address or distributed.Client (an address it cannot reach within
    CONNECT_TIMEOUT raises ConnectionError; without Dask installed, NotAvailable). workers:
    local threads (default: every core this process may run on). Zero cases, more than
    MAX_CASES, or workers or batch_size below 1 raise ValueError naming what is wrong. The rows
    keep base and duration for stability_map.plot where pandas can (set_sweep_info).
    """
    _whole("workers", workers, MAX_WORKERS)
    _whole("batch_size", batch_size)
    columns = {key: np.ascontiguousarray(values, dtype=float) for key, values in cases.items()}
    lengths = {len(v) for v in columns.values()}
    if len(lengths) > 1:
        raise ValueError("every varied key needs one value per case")
    count = lengths.pop() if lengths else 1
    if count == 0:
        raise ValueError("a sweep needs at least one case, got 0")
    if count > MAX_CASES:
        raise _too_many(count)
    _core.validate({**base, **{key: float(v[0]) for key, v in columns.items()}})
    settings = (float(duration), float(sample_rate), float(max_steps))
    _core.CaseSettings(*settings)  # refuses bad settings now, naming them

    client, own_client = _client(scheduler) if scheduler is not None else (None, False)
    try:
        return _run(base, columns, count, settings, duration, client, workers, batch_size, progress)
    finally:
        if own_client:
            client.close()


def _run(base, columns, count, settings, duration, client, workers, batch_size, progress):
    import pandas as pd

    if client is not None:
        workers = _workers(client)
    else:
        workers = workers or len(os.sched_getaffinity(0)) or 1  # the cores this process may use
    spans = _batches(count, workers, batch_size)
    bar = _progress_bar(count, progress)
    results = [None] * len(spans)
    if client is not None:
        from distributed import as_completed

        parts = [{k: v[a:b] for k, v in columns.items()} for a, b in spans]
        futures = client.map(run_batch, [base] * len(spans), parts, [settings] * len(spans), pure=False)
        index = {f.key: i for i, f in enumerate(futures)}
        for future in as_completed(futures):
            i = index[future.key]
            results[i] = future.result()
            if bar:
                bar.update(spans[i][1] - spans[i][0])
    else:
        with concurrent.futures.ThreadPoolExecutor(max_workers=workers) as pool:
            futures = {pool.submit(run_batch, base, {k: v[a:b] for k, v in columns.items()}, settings): i
                       for i, (a, b) in enumerate(spans)}
            for future in concurrent.futures.as_completed(futures):
                i = futures[future]
                results[i] = future.result()
                if bar:
                    bar.update(spans[i][1] - spans[i][0])
    if bar:
        bar.close()
    frame = {key: values for key, values in columns.items()}
    for name in OUTCOME_COLUMNS:
        parts = [r[name] for r in results]
        frame[name] = np.concatenate([np.asarray(p) for p in parts]) if parts else np.array([])
    rows = pd.DataFrame(frame)
    set_sweep_info(rows, base, duration)
    return rows


def set_sweep_info(rows, base, duration):
    """Keeps the sweep's base keys and duration with its rows, in DataFrame.attrs (pandas >= 1.0),
    where stability_map.plot finds them. pandas 0.25 (Ubuntu 20.04) has no attrs: there the rows
    carry nothing, and plot takes them as its base= and duration= arguments."""
    if hasattr(type(rows), "attrs"):
        rows.attrs["base"] = dict(base)
        rows.attrs["duration"] = float(duration)


def sweep_info(rows):
    """(base keys, duration) kept with the rows by set_sweep_info, or (None, None): pandas < 1.0,
    or rows that were not returned by run (read back from a CSV file)."""
    attrs = rows.attrs if hasattr(type(rows), "attrs") else {}
    return attrs.get("base"), attrs.get("duration")


def _parquet_engine():
    """None if pandas can write Parquet here, else why not."""
    for engine in ("pyarrow", "fastparquet"):
        try:
            __import__(engine)
            return None
        except ImportError:
            pass
    return "Parquet needs pyarrow or fastparquet, which Debian bookworm does not package: write .csv instead"


def _row_bytes(rows, fmt):
    if fmt == "parquet":  # into a buffer: pandas < 1.2 returns no bytes for a path of None
        buffer = io.BytesIO()
        rows.to_parquet(buffer, index=False)
        return buffer.getvalue()
    return rows.to_csv(index=False).encode()


def write(rows, path):
    """Writes the rows to exactly `path`: CSV (floats as Python's repr: the shortest text that
    reads back to the same double) or Parquet (needs pyarrow or fastparquet, which Debian
    bookworm does not package), by the extension; another extension, a directory, a missing
    directory or a failed write raise ValueError (the file is written whole or not at all)."""
    fmt = _cli.check_output(None, path, ROW_FORMATS)
    if fmt == "parquet" and _parquet_engine():
        raise ValueError(f"{_cli.short_path(path)}: {_parquet_engine()}")
    _cli.write_file(None, path, _row_bytes(rows, fmt))


def _keep(rows):
    """Saves rows that could not be written where asked in a new CSV file (the temporary
    directory, else the working one); says where."""
    data = _row_bytes(rows, "csv")
    for directory in (tempfile.gettempdir(), os.getcwd()):
        path = None
        try:
            fd, path = tempfile.mkstemp(prefix="sweep-rows-", suffix=".csv", dir=directory)
            with os.fdopen(fd, "wb") as f:
                f.write(data)
            return f"the {len(rows)} rows are in {path}"
        except OSError:
            if path:
                try:
                    os.remove(path)
                except OSError:
                    pass
    return f"the {len(rows)} rows could not be saved anywhere (no space in {tempfile.gettempdir()} nor here)"


def _write_stdout(text):
    try:
        sys.stdout.write(text)
        sys.stdout.flush()
    except OSError as error:
        try:  # nothing more reaches a closed or full stdout, not even Python's last flush at exit
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        except (OSError, AttributeError, ValueError):
            pass
        raise _cli.UsageError("--output", f"cannot write to stdout: {error.strerror or error}") from None


# --- command line ------------------------------------------------------------------------------

def _parse_vary(text):
    if "=" not in text or text.startswith("="):
        raise _cli.UsageError("--vary", f"expected KEY=LOW:HIGH[:N] or KEY=V1,V2,..., got {_cli.short(text)}")
    key, spec = text.split("=", 1)
    try:
        texts = spec.split(":" if ":" in spec else ",")
        if any("_" in t for t in texts):  # Python's float reads 1_0 as 10; --set and scene files refuse it
            raise ValueError
        parts = [float(p) for p in texts]
        if not all(math.isfinite(p) for p in parts):
            raise ValueError
        if ":" not in spec:
            return key, parts
        if len(parts) == 3:
            if parts[2] != int(parts[2]):
                raise ValueError
            return key, (parts[0], parts[1], int(parts[2]))
        if len(parts) == 2:
            return key, (parts[0], parts[1])
        raise ValueError
    except ValueError:
        raise _cli.UsageError(f"--vary {_cli.short(key, quote=False)}",
                              f"expected LOW:HIGH[:N] or V1,V2,... (finite numbers), got {_cli.short(spec)}") from None


def _options(args):
    """The keys of --set and the ranges of --vary; refuses what would be ignored or overridden."""
    if args.design == "grid":
        for option, value in (("--cases", args.cases), ("--seed", args.seed)):
            if value is not None:
                raise _cli.UsageError(option, "only for --design random or sobol (a grid has its own cases)")
    elif args.cases is None:
        raise _cli.UsageError("--cases", f"a {args.design} design needs --cases N")
    elif args.cases > MAX_CASES:
        raise _cli.UsageError("--cases", str(_too_many(args.cases)))
    if not args.plot:
        for option, value in (("--x", args.x), ("--y", args.y), ("--value", args.value)):
            if value is not None:
                raise _cli.UsageError(option, "only with --plot (it chooses what the map shows)")
    overrides = {}
    for item in args.set:
        if "=" not in item or item.startswith("="):
            raise _cli.UsageError("--set", f"expected KEY=VALUE, got {_cli.short(item)}")
        key, value = item.split("=", 1)
        if key in overrides:
            raise _cli.UsageError(f"--set {_cli.short(key, quote=False)}", "given twice")
        overrides[key] = value
    ranges = {}
    for item in args.vary:
        key, spec = _parse_vary(item)
        if key in ranges:
            raise _cli.UsageError(f"--vary {_cli.short(key, quote=False)}", "given twice")
        if key in overrides:
            raise _cli.UsageError(f"--set {_cli.short(key, quote=False)}",
                                  "also given by --vary (which one should hold?)")
        ranges[key] = spec
    return overrides, ranges


def _check_outputs(args):
    """Refuses, before any case runs, outputs that cannot be written as asked."""
    if args.output is not None and not args.output:
        raise _cli.UsageError("--output", "an empty file name; leave --output out to write to stdout")
    if args.plot is not None and not args.plot:
        raise _cli.UsageError("--plot", "an empty file name")
    if args.output:
        if _cli.check_output("--output", args.output, ROW_FORMATS) == "parquet" and _parquet_engine():
            raise _cli.UsageError("--output", f"{_cli.short_path(args.output)}: {_parquet_engine()}")
        try:
            if os.path.samefile(args.output, args.config):
                raise _cli.UsageError("--output", f"{_cli.short_path(args.output)} is the --config file")
        except OSError:
            pass
    if args.plot:
        _cli.check_output("--plot", args.plot, _cli.figure_formats())


def _blame(error, args, overrides, ranges):
    """The option that gave the key the core refused: `--option: message`."""
    key = getattr(error, "key", None)
    if key in ranges:
        return f"--vary: {error}"
    if key in overrides:
        return f"--set: {error}"
    return f"--config: {args.config}: {error}"


def main(argv=None):
    parser = _cli.Parser(
        prog="sweep", error_prog="sweep",
        description="Runs a scene over a grid or a random or Sobol sample of its keys, one row per case "
                    "(the outcome, event time, least R, largest tilt, energy balance, the hops, method), and draws a "
                    "stability map. Each case runs in the C++ core to --duration or its first terminal event (the tip's hops go on).",
        epilog="Example (the README's map): sweep --config config/fixed_tip.yaml --vary initial/spin=0:200:201 "
               "--vary initial/tilt=0:1.4:141 --output map.csv --plot map.png. Errors are one line naming the "
               "option, exit status 2; outputs are checked before the first case runs.")
    parser.add_argument("--config", required=True, help="scene file (YAML), e.g. config/fixed_tip.yaml")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="overrides one key of the scene file for every case (repeatable, once per key)")
    parser.add_argument("--vary", action="append", default=[], metavar="KEY=SPEC", required=True,
                        help="a key to vary, once per key: LOW:HIGH:N (grid axis), LOW:HIGH (random, sobol) or "
                             f"V1,V2,... (grid); at most {MAX_CASES:.0e} cases")
    parser.add_argument("--design", choices=["grid", "random", "sobol"], default="grid",
                        help="grid (default), random, or sobol (needs SciPy >= 1.7)")
    parser.add_argument("--cases", type=_cli.whole_number(1), help="number of cases of a random or sobol design")
    parser.add_argument("--seed", type=_cli.whole_number(0), help="seed of a random or sobol design (default 0)")
    parser.add_argument("--duration", type=float, default=DEFAULT_SETTINGS.duration,
                        help="[s] each case runs to it or its first terminal event (default %(default)g)")
    parser.add_argument("--sample-rate", type=float, default=DEFAULT_SETTINGS.sample_rate,
                        help="[Hz] samples of a time-stepper's case for its extremes (default %(default)g; exact needs "
                             "none)")
    parser.add_argument("--max-steps", type=float, default=DEFAULT_SETTINGS.max_steps,
                        help="integration steps a case may take (default %(default)g)")
    parser.add_argument("--output", help="rows as .csv or .parquet (default: CSV on stdout); if it cannot be "
                        "written after the run, the rows go to a new file in the temporary directory, named")
    parser.add_argument("--plot", help="stability map (outcome and event time over --x and --y) as .png, .svg, "
                        ".pdf, ...")
    parser.add_argument("--value", help="with --plot: numeric column shown in the map's second panel (default "
                        "event_time; e.g. final_tilt, max_hop_height, lift_offs)")
    parser.add_argument("--x", help="with --plot: key on the map's x axis (default: the first --vary)")
    parser.add_argument("--y", help="with --plot: key on the map's y axis (default: the second --vary)")
    parser.add_argument("--scheduler", help="Dask scheduler address (tcp://host:8786); default: this machine's cores. "
                        f"Needs Dask ({DASK_INSTALL})")
    parser.add_argument("--workers", type=_cli.whole_number(1, MAX_WORKERS),
                        help=f"local threads (default: every core; at most {MAX_WORKERS})")
    parser.add_argument("--batch-size", type=_cli.whole_number(1),
                        help=f"cases per task (default: 16 tasks per worker, at most {MAX_BATCH})")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar on stderr")
    args = parser.parse_args(argv)

    def fail(message):
        return _cli.fail("sweep", message)

    try:
        overrides, ranges = _options(args)
        _check_outputs(args)
    except _cli.UsageError as error:
        return fail(error)
    # Optional modules, refused before any work: Dask for a scheduler, SciPy's qmc for Sobol points.
    if args.scheduler is not None:
        try:
            _distributed()
        except NotAvailable as error:
            return fail(f"--scheduler: {error}")
    if args.design == "sobol":
        try:
            _sobol_engine()
        except NotAvailable as error:
            return fail(f"--design: {error}")
    try:
        file_keys = dict(_core.read_scene_file(args.config))
    except (ValueError, OSError) as error:  # SceneFileError is a ValueError
        return fail(f"--config: {error}")
    except MemoryError:
        return fail(f"--config: {_cli.short_path(args.config)}: too large to read")
    base = {**file_keys, **overrides}
    try:
        cases = design(ranges, args.design, args.cases, 0 if args.seed is None else args.seed)
    except ValueError as error:
        return fail(f"--vary: {error}")
    if args.design == "sobol" and args.cases & (args.cases - 1):
        print(f"sweep: warning: --cases {args.cases}: Sobol points are balanced for a power of 2 cases "
              f"(e.g. {1 << (args.cases.bit_length() - 1)} or {1 << args.cases.bit_length()})", file=sys.stderr)
    try:
        settings = _core.CaseSettings(args.duration, args.sample_rate, args.max_steps)
    except _core.InvalidParameter as error:
        option = "--" + error.key.replace("_", "-")
        message = str(error)
        return fail(f"{option}: {message[len(error.key) + 2:] if message.startswith(error.key + ': ') else message}")
    try:
        _core.validate({**base, **{k: float(v[0]) for k, v in cases.items()}}, require_all=True)
    except _core.InvalidParameter as error:
        return fail(_blame(error, args, overrides, ranges))
    value = args.value or "event_time"
    if args.plot:  # checked before the sweep runs, not after
        keys = list(cases)
        x, y = args.x or keys[0], args.y or (keys[1] if len(keys) > 1 else None)
        if y is None:
            return fail("--plot: a map needs two keys: vary a second key or give --y")
        for option, key in (("--x", x), ("--y", y)):
            if key not in cases:
                return fail(f"{option} {key}: not a varied key ({', '.join(keys)})")
        if x == y:
            return fail(f"--y {y}: the same key as --x (a map needs two)")
        numeric = [c for c in OUTCOME_COLUMNS if c not in ("outcome", "method", "message")] + keys
        if value not in numeric:
            return fail(f"--value {value}: not a numeric column ({', '.join(numeric)})")
    try:
        client, own_client = _client(args.scheduler) if args.scheduler is not None else (None, False)
    except ConnectionError as error:
        return fail(f"--scheduler: {error}")
    try:
        rows = run(base, cases, settings.duration, settings.sample_rate, settings.max_steps, client, args.workers,
                   args.batch_size, progress=not args.no_progress)
    except ConnectionError as error:
        return fail(f"--scheduler: {error}")
    except (ValueError, _core.InvalidParameter) as error:
        return fail(error)
    finally:
        if own_client:
            client.close()

    status = 0
    try:
        if args.output:
            fmt = _cli.extension(args.output)
            _cli.write_file("--output", args.output, _row_bytes(rows, fmt))
        else:
            _write_stdout(rows.to_csv(index=False))
    except _cli.UsageError as error:
        status = fail(f"{error}; {_keep(rows)}")
    if args.plot:
        from spinning_top import stability_map

        try:
            stability_map.plot(rows, x, y, args.plot, value=value, base=base, duration=settings.duration)
        except ValueError as error:
            status = fail(f"--plot: {error}")
    summary = rows["outcome"].value_counts().to_dict()
    hopped = int((rows["lift_offs"] > 0).sum())
    print(f"sweep: {len(rows)} cases: " + ", ".join(f"{v} {k}" for k, v in summary.items()) +
          (f"; the tip left the floor in {hopped}" if hopped else ""), file=sys.stderr)
    return status


if __name__ == "__main__":
    sys.exit(main())
