"""What a study costs: one trial's breakdown, the throughput of a LocalCluster of 1 and of 2
workers, the same through Slurm jobs, and the size of a study's results on disk and in memory.

    PYTHONPATH=build/python python python/benchmarks/bench_study.py breakdown --trials 20
    PYTHONPATH=build/python python python/benchmarks/bench_study.py scaling --trials 200
    PYTHONPATH=build/python python python/benchmarks/bench_study.py slurm --trials 200
    PYTHONPATH=build/python python python/benchmarks/bench_study.py size --from DIR --rows 10000

breakdown: trials of the default tolerance study (99 + 56 configurations, three stages, the
square and the circle with 30 cycles) run one after the other in this process, on one core: the
median time of each stage and of the whole trial. scaling: the same study's first `trials` trials
on a fresh LocalCluster of 1 worker, then of 2, timed from the first task submitted to the last
row written (the cluster's start-up is reported apart); efficiency = throughput(2) /
(2 throughput(1)). slurm: the same with dask-jobqueue's SLURMCluster on the Slurm cluster that
SLURM_CONF (or /etc/slurm) names, scale(jobs=1) then scale(jobs=2), jobs of 1 core and 1
single-threaded worker; the jobs' start is reported apart (as root on a machine without Slurm,
`python python/tests/slurm_node.py python python/benchmarks/bench_study.py slurm ...` runs it on
a one-node cluster started for it). size: the Parquet bytes per row of a finished study, and a
table of `rows` rows drawn from its own (each column resampled independently, every value made
distinct, so that they are as hard to compress as real ones) written and measured.
"""
from __future__ import annotations

import argparse
import os
import statistics
import sys
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


def _local_cluster(workers, directory):
    from distributed import LocalCluster

    return LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                        dashboard_address=None)


def _slurm_cluster(args):
    def start(jobs, directory):
        from dask_jobqueue import SLURMCluster

        cluster = SLURMCluster(queue=args.queue, cores=1, processes=1, memory=args.memory,
                               walltime=args.walltime, python=sys.executable,
                               interface=args.interface, local_directory=directory,
                               log_directory=os.path.join(directory, "logs"))
        cluster.scale(jobs=jobs)
        return cluster
    return start


def _timed_run(definition, workers, trials, directory, start_cluster=_local_cluster):
    from distributed import Client

    import pcr.study as study

    os.makedirs(directory)
    start = time.perf_counter()
    with start_cluster(workers, directory) as cluster, Client(cluster) as client:
        client.wait_for_workers(workers, timeout=600)
        client.run(lambda: __import__("pcr.study"))  # workers import pcr before the clock
        ready = time.perf_counter()
        table = study.run(definition, os.path.join(directory, "results"), trials=trials,
                          client=client, progress=False)
        done = time.perf_counter()
    return ready - start, done - ready, table


def scaling(args, start_cluster=_local_cluster, what="worker(s)"):
    import pcr.study as study

    definition = study.Study.load(args.study)
    per_level = -(-args.trials // len(definition.combinations()))
    results = {}
    with tempfile.TemporaryDirectory(dir=args.tmp) as tmp:
        for workers in (1, 2):
            startup, seconds, table = _timed_run(definition, workers, per_level,
                                                 os.path.join(tmp, f"w{workers}"), start_cluster)
            results[workers] = len(table) / seconds
            print(f"{workers} {what}: {len(table)} trials in {seconds:.1f} s "
                  f"({results[workers]:.2f} trials/s; cluster start {startup:.1f} s; "
                  f"{int(table['failure'].notna().sum())} failed)")
    print(f"efficiency of 2: {results[2] / (2 * results[1]):.3f} of twice 1's throughput "
          f"({os.cpu_count()} cores)")


def slurm(args):
    scaling(args, _slurm_cluster(args), "Slurm job(s) of 1 worker")


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
    for name in ("scaling", "slurm"):
        s = sub.add_parser(name)
        s.add_argument("--trials", type=int, default=200)
        s.add_argument("--study", default="tolerance", help="a built-in study or a TOML file")
        s.add_argument("--tmp", help="where the results go (a temporary directory in it; the "
                       "Slurm jobs must see it)")
        if name == "slurm":
            s.add_argument("--queue", help="the partition (default: Slurm's)")
            s.add_argument("--memory", default="1GB", help="per job (default: %(default)s)")
            s.add_argument("--walltime", default="01:00:00")
            s.add_argument("--interface", help="the network interface of the scheduler and "
                           "workers (default: dask-jobqueue's)")
    z = sub.add_parser("size")
    z.add_argument("--from", dest="source", required=True)
    z.add_argument("--rows", type=int, default=10000)
    args = p.parse_args()
    {"breakdown": breakdown, "scaling": scaling, "slurm": slurm, "size": size}[args.what](args)


if __name__ == "__main__":
    main()
