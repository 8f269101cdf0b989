"""What a study costs: one trial's breakdown, the throughput of a LocalCluster of 1 and of 2
workers, and the size of a study's results on disk and in memory.

    PYTHONPATH=build/python python python/benchmarks/bench_study.py breakdown --trials 20
    PYTHONPATH=build/python python python/benchmarks/bench_study.py scaling --trials 200
    PYTHONPATH=build/python python python/benchmarks/bench_study.py size --from DIR --rows 10000

breakdown: trials of the default tolerance study (99 + 56 configurations, three stages, the
square and the circle with 30 cycles) run one after the other in this process, on one core: the
median time of each stage and of the whole trial. scaling: the same study's first `trials` trials
on a fresh LocalCluster of 1 worker, then of 2, timed from the first task submitted to the last
row written (the cluster's start-up is reported apart); efficiency = throughput(2) /
(2 throughput(1)). size: the Parquet bytes per row of a finished study, and a table of `rows`
rows drawn from its own (each column resampled independently, every value made distinct, so that
they are as hard to compress as real ones) written and measured.
"""
from __future__ import annotations

import argparse
import os
import statistics
import tempfile
import time

import numpy as np


def breakdown(args):
    import pcr.study as study

    definition = study.Study.load(args.study)
    rows = []
    for trial in definition.trial_list()[:args.trials]:
        rows.append(study.run_trial(trial.factors, trial.seed))
    failed = [r["failure"] for r in rows if r["failure"]]
    columns = [c for c in rows[0] if c.startswith("time.")] + ["time_s"]
    print(f"{len(rows)} trials of {definition.name} in series on one core ({len(failed)} failed)")
    for c in columns:
        values = [r[c] for r in rows if r["failure"] is None]
        print(f"  {c:24s} median {statistics.median(values):.3f} s  "
              f"(min {min(values):.3f}, max {max(values):.3f})")


def _timed_run(definition, workers, trials, directory):
    from distributed import Client, LocalCluster

    import pcr.study as study

    start = time.perf_counter()
    with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                      dashboard_address=None) as cluster, Client(cluster) as client:
        client.run(lambda: __import__("pcr.study"))  # workers import pcr before the clock
        ready = time.perf_counter()
        table = study.run(definition, directory, trials=trials, client=client, progress=False)
        done = time.perf_counter()
    return ready - start, done - ready, table


def scaling(args):
    import pcr.study as study

    definition = study.Study.load(args.study)
    per_level = -(-args.trials // len(definition.combinations()))
    results = {}
    with tempfile.TemporaryDirectory() as tmp:
        for workers in (1, 2):
            startup, seconds, table = _timed_run(definition, workers, per_level,
                                                 os.path.join(tmp, f"w{workers}"))
            results[workers] = len(table) / seconds
            print(f"{workers} worker(s): {len(table)} trials in {seconds:.1f} s "
                  f"({results[workers]:.2f} trials/s; cluster start {startup:.1f} s; "
                  f"{int(table['failure'].notna().sum())} failed)")
    print(f"efficiency of 2 workers: {results[2] / (2 * results[1]):.3f} of twice 1 worker's "
          f"throughput ({os.cpu_count()} cores)")


def size(args):
    import pandas as pd
    import pyarrow as pa
    import pyarrow.parquet as pq

    import pcr.study as study

    table = study.read_results(args.source)
    parts = [os.path.join(args.source, n) for n in os.listdir(args.source)
             if n.startswith("part-")]
    on_disk = sum(os.path.getsize(p) for p in parts)
    print(f"{args.source}: {len(table)} rows, {len(table.columns)} columns, {len(parts)} files, "
          f"{on_disk / 1e6:.2f} MB on disk ({on_disk / len(table):.0f} bytes per row)")
    rng = np.random.default_rng(1)
    big = pd.DataFrame({c: table[c].to_numpy()[rng.integers(0, len(table), args.rows)]
                        for c in table.columns})
    big["trial"] = np.arange(args.rows)
    # Every value distinct, as in a real study (resampled ones repeat, and Parquet's dictionary
    # encoding would store them in a byte): outcomes times 1 + 1e-3 N(0, 1).
    for c in big.columns:
        if c.startswith(("table3.", "accuracy.", "parameters.", "time")):
            big[c] *= 1 + 1e-3 * rng.standard_normal(args.rows)
    with tempfile.TemporaryDirectory() as tmp:
        one = os.path.join(tmp, "one.parquet")
        pq.write_table(pa.Table.from_pandas(table, preserve_index=False), one,
                       compression="zstd")
        print(f"  the same rows in one file: {os.path.getsize(one) / 1e6:.2f} MB "
              f"({os.path.getsize(one) / len(table):.0f} bytes per row)")
        path = os.path.join(tmp, "big.parquet")
        pq.write_table(pa.Table.from_pandas(big, preserve_index=False), path,
                       compression="zstd")
        print(f"{args.rows} rows resampled from it, every value distinct: "
              f"{os.path.getsize(path) / 1e6:.2f} MB of Parquet (zstd, one file), "
              f"{big.memory_usage(deep=True).sum() / 1e6:.1f} MB in pandas")


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = p.add_subparsers(dest="what", required=True)
    b = sub.add_parser("breakdown")
    b.add_argument("--trials", type=int, default=20)
    b.add_argument("--study", default="tolerance")
    s = sub.add_parser("scaling")
    s.add_argument("--trials", type=int, default=200)
    s.add_argument("--study", default="tolerance")
    z = sub.add_parser("size")
    z.add_argument("--from", dest="source", required=True)
    z.add_argument("--rows", type=int, default=10000)
    args = p.parse_args()
    {"breakdown": breakdown, "scaling": scaling, "size": size}[args.what](args)


if __name__ == "__main__":
    main()
