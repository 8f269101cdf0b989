"""A one-node Slurm cluster on this machine, for the tests and the benchmarks.

munged, slurmctld and slurmd run as root in the foreground (no systemd), each in its own process
group, from a configuration generated in a temporary directory: a new munge key and socket, free
TCP ports, state and spool directories there, this host as the only node (its CPUs and memory),
one partition `normal`, no cgroups (proctrack/pgid, task/none), no accounting. Stopping it
cancels the jobs, ends every process it started (the jobs' too) and removes the directory.

    python python/tests/slurm_node.py COMMAND [ARG...]

runs COMMAND with SLURM_CONF naming the cluster, then stops it (the tests use SlurmNode).
"""
from __future__ import annotations

import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time

DAEMONS = ("munged", "slurmctld", "slurmd")
CLIENTS = ("sinfo", "squeue", "sbatch", "scancel", "scontrol")


def unavailable():
    """Why a one-node cluster cannot be started here, or None."""
    if os.name != "posix" or os.geteuid() != 0:
        return "a one-node Slurm cluster needs root (munged, slurmctld and slurmd run as root)"
    missing = [name for name in DAEMONS + CLIENTS if not shutil.which(name)]
    if missing:
        return (f"{', '.join(missing)} not found: install the Debian packages slurmctld, slurmd, "
                "slurm-client and munge (scripts/run.sh setup does)")
    return None


def _free_ports(count):
    sockets = [socket.socket() for _ in range(count)]
    try:
        for s in sockets:
            s.bind(("127.0.0.1", 0))
        return [s.getsockname()[1] for s in sockets]
    finally:
        for s in sockets:
            s.close()


def _memory_mb():
    with open("/proc/meminfo") as f:
        for line in f:
            if line.startswith("MemTotal:"):
                return int(line.split()[1]) // 1024
    raise RuntimeError("/proc/meminfo: no MemTotal")


class SlurmNode:
    """The cluster: `with SlurmNode() as node:` starts it and waits until its node is idle;
    `node.env` is os.environ with SLURM_CONF set, for the client commands."""

    def __init__(self, partition="normal", timeout=60.0):
        self.partition, self.timeout = partition, timeout
        self.directory = None
        self.processes = {}

    # ---- start ---------------------------------------------------------------------------
    def __enter__(self):
        try:
            self.start()
        except BaseException:
            self.stop()
            raise
        return self

    def __exit__(self, *exc):
        self.stop()

    def start(self):
        reason = unavailable()
        if reason:
            raise RuntimeError(reason)
        # munged wants every directory on its socket's path searchable by all and writable by
        # its owner only; the key readable by its owner only.
        self.directory = tempfile.mkdtemp(prefix="pcr-slurm-")
        os.chmod(self.directory, 0o755)
        for name in ("state", "spool"):
            os.mkdir(self.path(name))
        key = self.path("munge.key")
        fd = os.open(key, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
        with os.fdopen(fd, "wb") as f:
            f.write(os.urandom(128))  # 1024 bits, as mungekey makes
        self.node = socket.gethostname().split(".")[0]  # hostname -s: slurmctld checks it
        self.cpus = len(os.sched_getaffinity(0))
        self.memory_mb = _memory_mb()
        self.conf = self.path("slurm.conf")
        ctld_port, slurmd_port = _free_ports(2)
        with open(self.conf, "w") as f:
            f.write(f"""\
ClusterName=pcr
SlurmctldHost={self.node}(127.0.0.1)
SlurmctldPort={ctld_port}
SlurmdPort={slurmd_port}
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket={self.path("munge.sock")}
StateSaveLocation={self.path("state")}
SlurmdSpoolDir={self.path("spool")}
SlurmctldPidFile={self.path("slurmctld.pid")}
SlurmdPidFile={self.path("slurmd.pid")}
ProctrackType=proctrack/pgid
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SwitchType=switch/none
MpiDefault=none
MailProg=/bin/true
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
KillWait=5
NodeName={self.node} NodeAddr=127.0.0.1 CPUs={self.cpus} RealMemory={self.memory_mb} State=UNKNOWN
PartitionName={self.partition} Nodes=ALL Default=YES MaxTime=INFINITE State=UP
""")
        # SLURM_CONF in the daemons' environment too: slurmstepd and the jobs inherit it, which
        # is how stop() finds whatever of them is left.
        self.env = dict(os.environ, SLURM_CONF=self.conf)
        self._spawn("munged", ["munged", "--foreground", "--socket", self.path("munge.sock"),
                               "--key-file", key, "--pid-file", self.path("munged.pid"),
                               "--log-file", self.path("munged.log"),
                               "--seed-file", self.path("munged.seed")])
        self._wait(lambda: os.path.exists(self.path("munge.sock")), "munged's socket")
        self._spawn("slurmctld", ["slurmctld", "-D", "-f", self.conf])
        self._spawn("slurmd", ["slurmd", "-D", "-f", self.conf, "-N", self.node])
        self._wait(lambda: self.node_state() == "idle", f"node {self.node} idle in sinfo")
        return self

    def path(self, name):
        return os.path.join(self.directory, name)

    def _spawn(self, name, args):
        with open(self.path(f"{name}.out"), "w") as log:
            self.processes[name] = subprocess.Popen(
                args, stdin=subprocess.DEVNULL, stdout=log, stderr=subprocess.STDOUT,
                env=self.env, cwd=self.directory, start_new_session=True)

    def _wait(self, ready, what):
        deadline = time.monotonic() + self.timeout
        while not ready():
            ended = {n: p.returncode for n, p in self.processes.items() if p.poll() is not None}
            if ended or time.monotonic() > deadline:
                problem = (f"exited ({ended})" if ended else
                           f"not within {self.timeout:.0f} s")
                raise RuntimeError(f"one-node Slurm cluster: waiting for {what}: "
                                   f"{problem}\n{self.logs()}")
            time.sleep(0.2)

    def node_state(self):
        r = subprocess.run(["sinfo", "-h", "-N", "-o", "%T"], env=self.env,
                           capture_output=True, text=True, timeout=30)
        return r.stdout.strip() if r.returncode == 0 else None

    def logs(self):
        """The daemons' output and the configuration, for an error message."""
        parts = []
        for name in (*DAEMONS, "slurm.conf"):
            path = self.path(name if "." in name else f"{name}.out")
            if os.path.exists(path):
                with open(path, errors="replace") as f:
                    parts.append(f"---- {path}\n{f.read()[-6000:]}")
        return "\n".join(parts)

    # ---- the client commands ----------------------------------------------------------------
    def run(self, *args, check=True, timeout=60):
        """A Slurm command (sbatch, squeue, ...) against this cluster: its stdout."""
        r = subprocess.run(args, env=self.env, capture_output=True, text=True, timeout=timeout)
        if check and r.returncode != 0:
            raise RuntimeError(f"{' '.join(args)} exited with {r.returncode}: {r.stderr}")
        return r.stdout

    def jobs(self):
        """{job id: state} of the jobs squeue lists (pending, running, completing)."""
        out = self.run("squeue", "-h", "-o", "%i %T")
        return dict(line.split() for line in out.splitlines() if line.strip())

    def job_state(self, job):
        out = self.run("scontrol", "-o", "show", "job", str(job))
        return next(f.split("=", 1)[1] for f in out.split() if f.startswith("JobState="))

    # ---- stop ------------------------------------------------------------------------------
    def stop(self):
        """Cancels the jobs, ends the daemons' process groups and whatever the jobs left, and
        removes the directory; also after a failed start."""
        if self.directory is None:
            return
        try:
            if all(p.poll() is None for p in self.processes.values()) and \
                    len(self.processes) == len(DAEMONS):
                try:
                    self.run("scancel", "--partition", self.partition, timeout=30)
                    deadline = time.monotonic() + 30
                    while self.jobs() and time.monotonic() < deadline:
                        time.sleep(0.2)
                except (RuntimeError, subprocess.TimeoutExpired):
                    pass
            for name in reversed(DAEMONS):  # slurmd, slurmctld, then munged
                process = self.processes.get(name)
                if process is None:
                    continue
                _signal_group(process, signal.SIGTERM)
                try:
                    process.wait(timeout=15)
                except subprocess.TimeoutExpired:
                    pass
                _signal_group(process, signal.SIGKILL)
                process.wait()
            self._kill_leftovers()
        finally:
            shutil.rmtree(self.directory, ignore_errors=True)
            self.directory = None
            self.processes = {}

    def _kill_leftovers(self):
        """SIGKILL to every process that still has this cluster's SLURM_CONF in its environment
        (a job step or a job's child that outlived the daemons), but this one and its parents."""
        mine = f"SLURM_CONF={self.conf}".encode()
        spare, pid = set(), os.getpid()
        while pid > 1:
            spare.add(pid)
            try:
                with open(f"/proc/{pid}/stat") as f:
                    pid = int(f.read().rsplit(")", 1)[1].split()[1])
            except OSError:
                break
        for _ in range(3):
            found = []
            for entry in os.listdir("/proc"):
                if not entry.isdigit() or int(entry) in spare:
                    continue
                try:
                    with open(f"/proc/{entry}/environ", "rb") as f:
                        if mine in f.read().split(b"\0"):
                            found.append(int(entry))
                except OSError:
                    continue
            if not found:
                return
            for p in found:
                try:
                    os.kill(p, signal.SIGKILL)
                except OSError:
                    pass
            time.sleep(0.2)


def _signal_group(process, sig):
    try:
        os.killpg(process.pid, sig)
    except (ProcessLookupError, PermissionError):
        pass


def main(argv):
    if not argv or argv[0] in ("-h", "--help"):
        print(__doc__)
        return 0 if argv else 2
    reason = unavailable()
    if reason:
        print(f"slurm_node: {reason}", file=sys.stderr)
        return 2
    with SlurmNode() as node:
        print(f"slurm_node: node {node.node} ({node.cpus} CPUs, {node.memory_mb} MB) idle, "
              f"SLURM_CONF={node.conf}", file=sys.stderr)
        return subprocess.run(argv, env=node.env).returncode


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
