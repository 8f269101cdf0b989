"""pcr.study on a real Slurm cluster: a one-node cluster started on this machine (slurm_node.py:
munged, slurmctld and slurmd as root), the tests' small study through dask-jobqueue's
SLURMCluster as docs/studies.md shows it, and a `pcr-study run` batch job cancelled mid-study
(scancel) that the same job resumes; both give the LocalCluster's table, times aside.

ctest runs these apart (label `cluster`: `ctest -L cluster`); pytest alone: `-m cluster`.
"""
import os
import shlex
import sys
import time

import pytest

from slurm_node import SlurmNode, unavailable
from test_study import SMALL, _command, _without_times, small  # noqa: F401 (small: a fixture)

study = pytest.importorskip("pcr.study", reason="the [study] extra is not installed")
pd = pytest.importorskip("pandas")

pytestmark = pytest.mark.cluster


@pytest.fixture(scope="module")
def slurm():
    """The one-node cluster, with SLURM_CONF set in this process for the Slurm commands that
    dask-jobqueue runs; stopped (jobs, daemons, files) after the module, also on failure."""
    reason = unavailable()
    if reason:
        pytest.skip(reason)
    with SlurmNode() as node, pytest.MonkeyPatch.context() as patch:
        patch.setenv("SLURM_CONF", node.conf)
        yield node


def _logs(directory):
    """The jobs' output files, for a failure message."""
    out = []
    for name in sorted(os.listdir(directory)) if os.path.isdir(directory) else []:
        path = os.path.join(directory, name)
        if os.path.isfile(path):
            with open(path, errors="replace") as f:
                out.append(f"---- {path}\n{f.read()[-4000:]}")
    return "\n".join(out)


def _wait(condition, seconds, what, details=lambda: ""):
    deadline = time.monotonic() + seconds
    while not condition():
        if time.monotonic() > deadline:
            raise AssertionError(f"not within {seconds} s: {what}\n{details()}")
        time.sleep(0.1)


def test_a_study_runs_through_slurmcluster_on_slurm_jobs(slurm, small, tmp_path):
    """docs/studies.md's Python form: SLURMCluster, scale(jobs=2), pcr.study.run(client=...)."""
    SLURMCluster = pytest.importorskip(
        "dask_jobqueue", reason="dask-jobqueue is not installed (scripts/run.sh setup installs "
        "it)").SLURMCluster
    from distributed import Client

    definition, table, _ = small
    logs = tmp_path / "logs"
    with SLURMCluster(queue="normal", cores=1, processes=1, memory="1GB", walltime="00:10:00",
                      python=sys.executable, interface="lo", log_directory=str(logs),
                      local_directory=str(tmp_path)) as cluster:
        assert "#SBATCH -p normal" in cluster.job_script()
        cluster.scale(jobs=2)
        with Client(cluster) as client:
            try:
                client.wait_for_workers(2, timeout=120)
            except TimeoutError as e:
                raise AssertionError(f"{e}\nsqueue: {slurm.jobs()}\n{_logs(logs)}") from None
            # The workers are the Slurm jobs' processes, each in a job of its own.
            ids = client.run(lambda: os.environ.get("SLURM_JOB_ID"))
            jobs = slurm.jobs()
            assert len(set(ids.values())) == 2, ids
            assert all(jobs.get(i) == "RUNNING" for i in ids.values()), (ids, jobs)
            remote = study.run(definition, tmp_path / "slurm", client=client, progress=False)
    pd.testing.assert_frame_equal(_without_times(remote), _without_times(table))
    # Closing the cluster cancelled its jobs.
    _wait(lambda: not set(ids.values()) & set(slurm.jobs()), 60, "the worker jobs end",
          lambda: str(slurm.jobs()))


def test_a_study_job_cancelled_mid_study_resumes_to_the_same_table(slurm, small, tmp_path):
    """`pcr-study run` as a batch job, cancelled with scancel once some trials are written;
    the same job submitted again finishes the study."""
    definition, table, _ = small
    path = tmp_path / "small.toml"
    path.write_text(SMALL)
    out = tmp_path / "results"
    # One worker, one trial per task, rows written every second: the 20 trials take several
    # seconds after the first file, which is when the job is cancelled.
    command = _command("run", str(path), "--output", str(out), "--workers", "1",
                       "--batch-size", "1", "--flush-seconds", "1", "--quiet")
    script = tmp_path / "study.sh"
    script.write_text("#!/bin/bash\n#SBATCH --job-name=pcr-study\n#SBATCH --cpus-per-task=1\n"
                      f"#SBATCH --time=00:10:00\n#SBATCH --chdir={tmp_path}\n"
                      f"#SBATCH --output={tmp_path}/job-%j.out\n{shlex.join(command)}\n")
    job = slurm.run("sbatch", "--parsable", str(script)).strip().split(";")[0]

    def written():
        return any(p.name.startswith("part-") for p in out.glob("*.parquet")) \
            if out.is_dir() else False

    _wait(lambda: written() or job not in slurm.jobs(), 300, "a first part file",
          lambda: _logs(tmp_path))
    assert job in slurm.jobs(), "the job ended before its first file\n" + _logs(tmp_path)
    slurm.run("scancel", job)
    _wait(lambda: job not in slurm.jobs(), 60, f"job {job} leaves the queue",
          lambda: str(slurm.jobs()))
    assert slurm.job_state(job) == "CANCELLED"
    partial = study.read_results(out)
    assert 0 < len(partial) < 20, "cancelled too late to test a resume"

    # Run the command again: the same job, to completion (polled here: sbatch --wait polls
    # at up to 10 s).
    job2 = slurm.run("sbatch", "--parsable", str(script)).strip().split(";")[0]
    _wait(lambda: job2 not in slurm.jobs(), 600, f"job {job2} ends", lambda: _logs(tmp_path))
    assert slurm.job_state(job2) == "COMPLETED", _logs(tmp_path)
    resumed = study.read_results(out)
    pd.testing.assert_frame_equal(_without_times(resumed), _without_times(table))
    # The trials written before the cancel were not run again.
    first = partial.set_index("trial")["time_s"]
    assert (resumed.set_index("trial").loc[first.index, "time_s"] == first).all()
    assert f"20 trials in {out} (0 failed)" in (tmp_path / f"job-{job2}.out").read_text()
