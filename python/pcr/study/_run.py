"""Running a study on Dask: trials batched into tasks, finished rows flushed to the results
store as they come, a progress line on stderr."""
from __future__ import annotations

import contextlib
import logging
import math
import os
import sys
import time

import pcr

from ._definition import Study
from ._store import ResultStore, read_results
from ._trial import (FACTORS, check_applicable, factor_values, load_robot, run_trial,
                     study_columns)


def run_batch(trials, robots):
    """The rows of a batch of trials (a Dask task): [(index, replicate, seed, factors)]."""
    rows = []
    for index, replicate, seed, factors in trials:
        row = run_trial(factors, seed, robots)
        row.update(factor_values(factors))
        row.update(trial=index, replicate=replicate, seed=seed)
        rows.append(row)
    return rows


def _robots(study):
    """The robot JSON texts the trials name (files are read here, once, not by every worker)."""
    names = {c.get("robot", FACTORS["robot"].default) for c in study.combinations()}
    texts = {}
    for name in names:
        texts[name] = load_robot(name).to_json()
    return texts


def _check(study, robots):
    """ValueError, before any trial runs, for a combination that sets a factor its robot's kind
    (planar or spatial) does not have."""
    for combination in study.combinations():
        robot = pcr.Robot.from_json(robots[combination.get("robot", FACTORS["robot"].default)])
        check_applicable(combination, robot, f"study {study.name!r}")


class Progress:
    """Trials done, failed, the rate and an estimated time left, on one line of `stream` (redrawn
    on a terminal, else printed every `every` seconds and at the end)."""

    def __init__(self, total, done, stream=sys.stderr, every=30.0):
        self.total, self.done, self.failed = total, done, 0
        self.stream, self.every = stream, every
        self.tty = hasattr(stream, "isatty") and stream.isatty()
        self.start = self.last = time.monotonic()
        self.new = 0

    def update(self, rows):
        self.done += len(rows)
        self.new += len(rows)
        self.failed += sum(r["failure"] is not None for r in rows)
        now = time.monotonic()
        if self.tty or now - self.last >= self.every or self.done == self.total:
            self.last = now
            self._draw(now)

    def _draw(self, now):
        rate = self.new / max(now - self.start, 1e-9)
        left = (self.total - self.done) / rate if rate > 0 else math.inf
        eta = "?" if not math.isfinite(left) else time.strftime("%H:%M:%S", time.gmtime(left))
        line = (f"{self.done}/{self.total} trials, {self.failed} failed, "
                f"{rate:.2f} trials/s, {eta} left")
        if self.tty:
            self.stream.write("\r" + line + ("\n" if self.done == self.total else ""))
        else:
            self.stream.write(line + "\n")
        self.stream.flush()


@contextlib.contextmanager
def _client(client, scheduler, workers):
    """The given client, a client of the scheduler at `scheduler`, or an embedded LocalCluster of
    `workers` single-threaded processes (default: one per core)."""
    if client is not None:
        yield client
        return
    from distributed import Client, LocalCluster

    if scheduler is not None:
        with Client(scheduler) as c:
            yield c
        return
    if workers is None:
        workers = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") \
            else os.cpu_count() or 1
    # Ceres logs (glog) each stage a failing trial stops; the trial's row says why already.
    env = {"GLOG_minloglevel": os.environ.get("GLOG_minloglevel", "3")}
    with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                      dashboard_address=None, silence_logs=logging.ERROR, env=env) as cluster, \
            Client(cluster) as c:
        yield c


def _workers(client):
    return max(1, len(client.scheduler_info().get("workers", {})))


def run(study, output, *, trials=None, workers=None, client=None, scheduler=None,
        batch_size=None, progress=True, flush_seconds=10.0):
    """Runs `study` (a Study, a built-in study's name or a TOML path) into the Parquet dataset
    `output` and returns its table (pandas DataFrame, ``read_results``).

    trials: trials per combination of levels (default: the study's). A directory that holds
    part of the same study is resumed: only the missing trials run, and the table is the one an
    uninterrupted run gives (less the times). Execution: `client` (a dask.distributed Client),
    else `scheduler` (an address), else a LocalCluster of `workers` processes. Trials go out in
    tasks of `batch_size` (default: up to 8, and at least 4 tasks per worker); finished rows are
    written every `flush_seconds`, and when the study stops, by KeyboardInterrupt too.
    """
    if not isinstance(study, Study):
        study = Study.load(study)
    if trials is not None:
        if isinstance(trials, bool) or not isinstance(trials, int) or trials < 1:
            raise ValueError(f"trials = {trials!r}: expected a whole number >= 1")
        study = study.replace(trials=trials)
    if batch_size is not None and (not isinstance(batch_size, int) or batch_size < 1):
        raise ValueError(f"batch_size = {batch_size!r}: expected a whole number >= 1")
    if workers is not None and (not isinstance(workers, int) or workers < 1):
        raise ValueError(f"workers = {workers!r}: expected a whole number >= 1")
    if not flush_seconds >= 0:
        raise ValueError(f"flush_seconds = {flush_seconds!r}: expected a number >= 0")
    robots = _robots(study)
    _check(study, robots)
    store = ResultStore(output, study, study_columns(robots), robots)
    done = store.done()
    todo = [t for t in study.trial_list() if t.index not in done]
    bar = Progress(study.trials * len(study.combinations()), len(done),
                   stream=sys.stderr if progress is True else progress) if progress else None
    if todo:
        with _client(client, scheduler, workers) as c:
            _execute(c, todo, robots, store, bar, batch_size, flush_seconds)
    return read_results(output)


def _execute(client, todo, robots, store, bar, batch_size, flush_seconds):
    from distributed import as_completed

    if batch_size is None:
        batch_size = max(1, min(8, len(todo) // (4 * _workers(client))))
    batches = [[(t.index, t.replicate, t.seed, t.factors) for t in todo[i:i + batch_size]]
               for i in range(0, len(todo), batch_size)]
    robots_future = client.scatter(robots, broadcast=True)
    futures = [client.submit(run_batch, b, robots_future, pure=False) for b in batches]
    batch_of = dict(zip((f.key for f in futures), batches))
    pending, last_flush = [], time.monotonic()
    try:
        for future in as_completed(futures):
            try:
                rows = future.result()
            except Exception as e:  # a worker that died under a trial: its batch fails
                rows = [_failed_row(t, f"worker: {type(e).__name__}: {e}")
                        for t in batch_of[future.key]]
            future.release()
            pending += rows
            if bar:
                bar.update(rows)
            if time.monotonic() - last_flush >= flush_seconds:
                store.write(pending)
                pending, last_flush = [], time.monotonic()
    finally:
        store.write(pending)  # the finished trials, also when stopped
        for f in futures:
            f.cancel()


def _failed_row(trial, reason):
    index, replicate, seed, factors = trial
    row = factor_values(factors)
    row.update(trial=index, replicate=replicate, seed=seed, failure=reason)
    return row
