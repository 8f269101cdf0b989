"""Rows in the order users have them (shuffled across the stroke box, long jumps), on random
robots drawn inside the paper's intervals: `pcr fk`, `pcr ik` and the Python batches give each
row the cold solve's equilibrium (a single solve from home), and with path=True / --path each row
is continued from the one before."""
import csv
import io
import subprocess

import numpy as np
import pytest

import pcr


def _random_robot(rng):
    """The default robot with every limb parameter drawn inside the paper's half-widths."""
    robot = pcr.Robot.default()
    for i in range(robot.num_limbs):
        limb = robot.limbs[i]
        robot = robot.with_limb(
            i, A=np.asarray(limb.A) + rng.uniform(-160e-6, 160e-6, 2),
            B=np.asarray(limb.B) + rng.uniform(-160e-6, 160e-6, 2),
            alpha=limb.alpha + rng.uniform(-5e-3, 5e-3),
            beta=limb.beta + rng.uniform(-5e-3, 5e-3),
            gamma=limb.gamma + rng.uniform(-5e-3, 5e-3),
            l=limb.l + rng.uniform(-126e-6, 126e-6), d=limb.d + rng.uniform(-20e-6, 20e-6))
    return robot


def _cli(cli, command, robot_file, rows, header, *extra):
    text = ",".join(header) + "\n" + "".join(",".join(repr(float(v)) for v in r) + "\n"
                                             for r in rows)
    out = subprocess.run([cli, command, "--robot", robot_file, *extra], input=text,
                         capture_output=True, text=True, check=False, timeout=300)
    assert out.returncode in (0, 1), out.stderr
    return list(csv.DictReader(io.StringIO(out.stdout)))


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_rows_are_the_cold_solves(cli, tmp_path, seed):
    rng = np.random.default_rng(seed)
    robot = _random_robot(rng)
    robot_file = str(tmp_path / "robot.json")
    robot.save(robot_file)
    q = rng.uniform(-6e-3, 6e-3, size=(30, 3))  # scattered, in random order
    cold = [robot.forward(row) for row in q]
    assert sum(s.converged for s in cold) >= 5
    batch = robot.forward(q)
    rows = _cli(cli, "fk", robot_file, q, ["q1", "q2", "q3"])
    for k, s in enumerate(cold):
        assert batch.status[k] == rows[k]["status"] == s.status, k
        if s.converged:
            assert np.array_equal(batch.pose[k], s.pose.to_array()), k
            assert [float(rows[k][c]) for c in ("x", "y", "theta")] == pytest.approx(
                s.pose.to_array(), abs=1e-15)

    poses = np.array([s.pose.to_array() for s in cold if s.converged])
    rng.shuffle(poses)
    cold_ik = [robot.inverse(p) for p in poses]
    batch_ik = robot.inverse(poses)
    rows_ik = _cli(cli, "ik", robot_file, poses, ["x", "y", "theta"])
    for k, s in enumerate(cold_ik):
        assert batch_ik.status[k] == rows_ik[k]["status"] == s.status, k
        if s.converged:
            assert np.array_equal(batch_ik.q[k], s.q), k
            assert [float(rows_ik[k][f"q{i}"]) for i in (1, 2, 3)] == pytest.approx(s.q, abs=1e-15)


def test_a_path_continues_each_row_from_the_one_before(cli, tmp_path):
    robot = pcr.Robot.default()
    robot_file = str(tmp_path / "robot.json")
    robot.save(robot_file)
    q = np.cumsum(np.random.default_rng(4).uniform(-1e-3, 1e-3, size=(12, 3)), axis=0)
    batch = robot.forward(q, path=True)
    rows = _cli(cli, "fk", robot_file, q, ["q1", "q2", "q3"], "--path")
    previous = None
    for k in range(len(q)):
        s = robot.forward(q[k], warm_start=previous)
        previous = s if s.converged else None
        assert batch.status[k] == rows[k]["status"] == s.status
        assert batch.iterations[k] == int(rows[k]["iterations"]) == s.iterations
        assert np.array_equal(batch.pose[k], s.pose.to_array())
    # --through-folds only with --path
    out = subprocess.run([cli, "fk", "--through-folds"], input="q1,q2,q3\n0,0,0\n",
                         capture_output=True, text=True, check=False, timeout=60)
    assert out.returncode != 0 and "--path" in out.stderr
