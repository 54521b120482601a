"""Parameter sweeps: many cases of one scene, each run by the C++ core to a duration or to its
first terminal event (a hop goes on: issue 18), one row per case (issue 11).

    import spinning_top as st
    from spinning_top import sweep
    base = st.load_scene("config/fixed_tip.yaml")
    cases = sweep.design({"initial/spin": (0, 200, 101), "initial/tilt": (0, 1.4, 71)})
    rows = sweep.run(base, cases)                      # all local cores
    rows = sweep.run(base, cases, scheduler="tcp://host:8786")   # a Dask cluster

A design is a dict key -> numpy array (one value per case). The rows are a pandas DataFrame:
the varied keys, then the outcome columns of ``OUTCOME_COLUMNS``. Cases are run in batches by
``_core.run_cases`` without the GIL, on a thread pool (local) or as Dask tasks (cluster); each
case depends on its own configuration only, so the rows are the same, bit for bit, whichever
runs them and however they are batched.

Command line: ``python3 -m spinning_top.sweep --help``.
"""
import argparse
import concurrent.futures
import math
import os
import sys

import numpy as np

from spinning_top import _core

#: The columns each case adds to its row, after the varied keys: name -> what it holds (the unit
#: first), in order. The core's run_cases writes them (its one list of them).
OUTCOME_COLUMNS = dict(_core.outcome_columns())

#: A case's settings unless told otherwise: the core's (CaseSettings).
DEFAULT_SETTINGS = _core.CaseSettings()

#: Cases per batch at most: ~0.1 s of fixed-tip work, small against a Dask task's ~1 ms cost.
MAX_BATCH = 4096


def design(ranges, kind="grid", cases=None, seed=0):
    """The cases of a sweep: key -> array of values.

    ranges: key -> (low, high, n) for a grid axis, (low, high) for a random or Sobol axis, or an
    explicit list of values (grid only). kind: "grid" (every combination, the first key varying
    slowest), "random" (uniform, numpy's PCG64 seeded with `seed`) or "sobol" (scrambled Sobol
    points, scipy.stats.qmc, seeded); `cases` is the number of random or Sobol cases.
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
                if int(n) != n or n < 1:
                    raise ValueError(f"{key}: a grid axis needs a whole number of points >= 1, got {n}")
                axes.append(np.linspace(float(low), float(high), int(n)))
            elif isinstance(spec, tuple) and len(spec) == 2:
                raise ValueError(f"{key}: a grid axis is (low, high, n) (LOW:HIGH:N) or a list of values; "
                                 "(low, high) is a range of a random or sobol design")
            else:
                axes.append(np.asarray(spec, dtype=float).ravel())
        mesh = np.meshgrid(*axes, indexing="ij")
        return {key: m.ravel() for key, m in zip(keys, mesh)}
    if kind not in ("random", "sobol"):
        raise ValueError(f"design: kind must be grid, random or sobol, got {kind!r}")
    if cases is None or int(cases) != cases or cases < 1:
        raise ValueError(f"a {kind} design needs cases >= 1, got {cases}")
    bounds = []
    for key in keys:
        spec = ranges[key]
        if not (isinstance(spec, tuple) and len(spec) == 2):
            raise ValueError(f"{key}: a {kind} axis is (low, high), got {spec!r}")
        bounds.append((float(spec[0]), float(spec[1])))
    if kind == "random":
        unit = np.random.default_rng(seed).random((int(cases), len(keys)))
    else:
        from scipy.stats import qmc

        sampler = qmc.Sobol(d=len(keys), scramble=True, seed=seed)
        m = math.log2(cases)
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
    from distributed import Client

    return scheduler if isinstance(scheduler, Client) else Client(scheduler)


def run(base, cases, duration=DEFAULT_SETTINGS.duration, sample_rate=DEFAULT_SETTINGS.sample_rate,
        max_steps=DEFAULT_SETTINGS.max_steps, scheduler=None, workers=None, batch_size=None, progress=False):
    """Runs every case; returns a pandas DataFrame, one row per case in the design's order.

    base: the keys every case shares (e.g. load_scene(...)); cases: design(...). The base with
    each varied key's first value is validated first, so a bad key or base value raises
    InvalidParameter before anything runs; a case the core refuses for its own values (C > 2A
    somewhere in a sweep of C) is a row with outcome "refused" and the core's message.
    scheduler: None for this machine's cores (threads: the core runs without the GIL), or a
    Dask scheduler address or distributed.Client. workers: local threads (default: every core
    this process may run on).
    """
    import pandas as pd

    columns = {key: np.ascontiguousarray(values, dtype=float) for key, values in cases.items()}
    lengths = {len(v) for v in columns.values()}
    if len(lengths) > 1:
        raise ValueError("every varied key needs one value per case")
    count = lengths.pop() if lengths else 1
    _core.validate({**base, **{key: float(v[0]) for key, v in columns.items()}})
    settings = (float(duration), float(sample_rate), float(max_steps))
    _core.CaseSettings(*settings)  # refuses bad settings now, naming them

    client = _client(scheduler) if scheduler is not None else None
    if client is not None:
        workers = max(1, sum(client.nthreads().values()))
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
    rows.attrs["base"] = dict(base)
    rows.attrs["duration"] = float(duration)
    return rows


def write(rows, path):
    """CSV (floats as Python's repr: the shortest text that reads back to the same double) or
    Parquet (needs pyarrow or fastparquet, which Debian bookworm does not package)."""
    path = str(path)
    if path.endswith(".parquet"):
        try:
            rows.to_parquet(path, index=False)
        except ImportError as error:
            raise SystemExit(f"sweep: --output {path}: Parquet needs pyarrow or fastparquet ({error}); "
                             "Debian bookworm packages neither: write .csv instead")
    else:
        rows.to_csv(path, index=False)


# --- command line ------------------------------------------------------------------------------

def _parse_vary(text):
    if "=" not in text:
        raise ValueError(f"--vary: expected KEY=LOW:HIGH[:N] or KEY=V1,V2,..., got {text!r}")
    key, spec = text.split("=", 1)
    try:
        if ":" in spec:
            parts = [float(p) for p in spec.split(":")]
            if len(parts) == 3:
                if parts[2] != int(parts[2]):
                    raise ValueError
                return key, (parts[0], parts[1], int(parts[2]))
            if len(parts) == 2:
                return key, (parts[0], parts[1])
            raise ValueError
        return key, [float(p) for p in spec.split(",")]
    except ValueError:
        raise ValueError(f"--vary {key}: expected LOW:HIGH[:N] or V1,V2,... (numbers), got {spec!r}") from None


def main(argv=None):
    parser = argparse.ArgumentParser(
        prog="sweep",
        description="Runs a scene over a grid or a random or Sobol sample of its keys, one row per case "
                    "(the outcome, event time, least R, largest tilt, energy balance, the hops, method), and draws a "
                    "stability map. Each case runs in the C++ core to --duration or its first terminal event (the tip's hops go on).",
        epilog="Example (the README's map): sweep --config config/fixed_tip.yaml --vary initial/spin=0:200:201 "
               "--vary initial/tilt=0:1.4:141 --output map.csv --plot map.png")
    parser.add_argument("--config", required=True, help="scene file (YAML), e.g. config/fixed_tip.yaml")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="overrides one key of the scene file for every case (repeatable)")
    parser.add_argument("--vary", action="append", default=[], metavar="KEY=SPEC", required=True,
                        help="a key to vary: LOW:HIGH:N (grid axis), LOW:HIGH (random, sobol) or V1,V2,... (grid)")
    parser.add_argument("--design", choices=["grid", "random", "sobol"], default="grid")
    parser.add_argument("--cases", type=int, help="number of cases of a random or sobol design")
    parser.add_argument("--seed", type=int, default=0, help="seed of a random or sobol design (default 0)")
    parser.add_argument("--duration", type=float, default=DEFAULT_SETTINGS.duration,
                        help="[s] each case runs to it or its first terminal event (default %(default)g)")
    parser.add_argument("--sample-rate", type=float, default=DEFAULT_SETTINGS.sample_rate,
                        help="[Hz] samples of a time-stepper's case for its extremes (default %(default)g; exact needs "
                             "none)")
    parser.add_argument("--max-steps", type=float, default=DEFAULT_SETTINGS.max_steps,
                        help="integration steps a case may take (default %(default)g)")
    parser.add_argument("--output", help="rows as .csv or .parquet (default: CSV on stdout)")
    parser.add_argument("--plot", help="stability map as PNG (outcome and event time over --x and --y)")
    parser.add_argument("--value", default="event_time",
                        help="numeric column shown in the map's second panel (default event_time; e.g. final_tilt, "
                             "max_hop_height, lift_offs)")
    parser.add_argument("--x", help="key on the map's x axis (default: the first --vary)")
    parser.add_argument("--y", help="key on the map's y axis (default: the second --vary)")
    parser.add_argument("--scheduler", help="Dask scheduler address (tcp://host:8786); default: this machine's cores")
    parser.add_argument("--workers", type=int, help="local threads (default: every core)")
    parser.add_argument("--batch-size", type=int, help=f"cases per task (default: 16 tasks per worker, at most {MAX_BATCH})")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar on stderr")
    args = parser.parse_args(argv)

    def fail(message):
        print(f"sweep: error: {message}", file=sys.stderr)
        return 2

    try:
        base = dict(_core.read_scene_file(args.config))
    except _core.SceneFileError as error:
        return fail(f"--config: {error}")
    for item in args.set:
        if "=" not in item or item.startswith("="):
            return fail(f"--set: expected key=value, got {item!r}")
        key, value = item.split("=", 1)
        base[key] = value
    try:
        ranges = dict(_parse_vary(v) for v in args.vary)
        cases = design(ranges, args.design, args.cases, args.seed)
        _core.validate({**base, **{k: float(v[0]) for k, v in cases.items()}}, require_all=True)
        if args.plot:  # checked before the sweep runs, not after
            keys = list(cases)
            x, y = args.x or keys[0], args.y or (keys[1] if len(keys) > 1 else None)
            if y is None:
                raise ValueError("--plot needs two keys: vary a second key or give --y")
            for option, key in (("--x", x), ("--y", y)):
                if key not in cases:
                    raise ValueError(f"{option} {key}: not a varied key ({', '.join(keys)})")
            numeric = [c for c in OUTCOME_COLUMNS if c not in ("outcome", "method", "message")] + keys
            if args.value not in numeric:
                raise ValueError(f"--value {args.value}: not a numeric column ({', '.join(numeric)})")
        rows = run(base, cases, args.duration, args.sample_rate, args.max_steps, args.scheduler, args.workers,
                   args.batch_size, progress=not args.no_progress)
    except (ValueError, _core.InvalidParameter) as error:
        return fail(error)
    if args.output:
        write(rows, args.output)
    else:
        rows.to_csv(sys.stdout, index=False)
    if args.plot:
        from spinning_top import stability_map

        stability_map.plot(rows, x, y, args.plot, value=args.value)
    summary = rows["outcome"].value_counts().to_dict()
    hopped = int((rows["lift_offs"] > 0).sum())
    print(f"sweep: {len(rows)} cases: " + ", ".join(f"{v} {k}" for k, v in summary.items()) +
          (f"; the tip left the floor in {hopped}" if hopped else ""), file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
