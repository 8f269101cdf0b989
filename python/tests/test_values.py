"""Value types travel: pickling (multiprocessing, Dask), copy.copy and copy.deepcopy of every
value pcr hands out, and the sequence and array views of a Pose."""
import concurrent.futures
import copy
import multiprocessing
import pickle

import numpy as np
import pytest

import pcr


def _values(robot):
    single = robot.forward([0.002, -0.001, 0.0005], shapes=True)
    batch = robot.forward(np.array([[0.001, 0.0, 0.0], [0.0, 0.002, -0.001], [0.5, 0.0, 0.0]]))
    options = pcr.SolverOptions().replace(max_iterations=17, check_stability=False,
                                          through_folds=True, position_accuracy=3e-9)
    return {
        "Pose": pcr.Pose(0.001, -0.002, 0.03),
        "Limb": robot.limbs[1],
        "Extrinsics": robot.extrinsics,
        "Uncertainty": robot.uncertainty,
        "LimbUncertainty": robot.uncertainty.limbs[2],
        "SolverOptions": options,
        "Robot": robot,
        "Solution": single,
        "BatchResult": batch,
    }


def _state(value):
    """Everything a value shows to Python, for comparing a copy with its original."""
    if isinstance(value, pcr.Robot):
        return value.to_json()
    if isinstance(value, pcr.SolveStatus):
        return value.name
    if isinstance(value, (int, float, str, bool, type(None))):
        return value
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, (list, tuple)):
        return [_state(v) for v in value]
    out = {}
    for name in dir(type(value)):
        if name.startswith("_") or callable(getattr(value, name)):
            continue
        out[name] = _state(getattr(value, name))
    return out


@pytest.mark.parametrize("name", ["Pose", "Limb", "Extrinsics", "Uncertainty", "LimbUncertainty",
                                  "SolverOptions", "Robot", "Solution", "BatchResult"])
def test_every_value_pickles_and_copies_to_an_equal_value(robot, name):
    value = _values(robot)[name]
    expected = repr(_state(value))  # repr: NaN compares equal to itself as text
    for twin in (pickle.loads(pickle.dumps(value)), copy.copy(value), copy.deepcopy(value)):
        assert type(twin) is type(value)
        assert repr(_state(twin)) == expected


def test_copies_do_not_share_their_values(robot):
    options = pcr.SolverOptions()
    other = copy.copy(options)
    other.max_iterations = 3
    assert options.max_iterations != 3
    uncertainty = copy.deepcopy(robot.uncertainty)
    uncertainty.limbs[0].l = 1.0
    assert robot.uncertainty.limbs[0].l != 1.0
    limb = pickle.loads(pickle.dumps(robot.limbs[0]))
    limb.A[0] = 0.5
    assert robot.limbs[0].A[0] != 0.5
    solution = robot.forward([0.001, 0.0, 0.0], shapes=True)
    deep = copy.deepcopy(solution)
    deep.shapes[0][0, 0] = 99.0
    assert solution.shapes[0][0, 0] != 99.0


def test_an_unpickled_solution_warm_starts_the_same_solve(robot):
    # The pickle leaves the solver's factorised Jacobian behind: the warm solve from the copy
    # evaluates its own, and lands on the same configuration.
    start = robot.forward([0.002, -0.001, 0.0005])
    moved = [0.00201, -0.00099, 0.00051]
    direct = robot.forward(moved, warm_start=start)
    via_pickle = robot.forward(moved, warm_start=pickle.loads(pickle.dumps(start)))
    assert direct.converged and via_pickle.converged
    assert via_pickle.q == pytest.approx(direct.q, abs=0)
    assert via_pickle.pose.to_array() == pytest.approx(direct.pose.to_array(), abs=1e-12)


def _solve_row(args):
    robot, options, q = args
    s = robot.forward(q, options=options)
    return s


def test_solves_run_in_worker_processes(robot):
    # What Dask and multiprocessing do: the robot, the options and the results cross process
    # boundaries by pickle, and the answers are those of the same solves in this process.
    options = pcr.SolverOptions().replace(check_stability=False)
    rng = np.random.default_rng(3)
    rows = [(robot.with_limb(i % 3, l=0.030 + 1e-5 * i), options, rng.uniform(-0.004, 0.004, 3))
            for i in range(6)]
    with concurrent.futures.ProcessPoolExecutor(
            2, mp_context=multiprocessing.get_context("spawn")) as pool:
        remote = list(pool.map(_solve_row, rows))
    for args, result in zip(rows, remote):
        local = _solve_row(args)
        assert result.status == local.status
        assert result.stable is None  # the options crossed too
        assert result.pose.to_array() == pytest.approx(local.pose.to_array(), abs=0)


def test_a_bad_pickled_state_is_refused():
    with pytest.raises(ValueError, match="Solution"):
        pcr.Solution.__new__(pcr.Solution).__setstate__((1, 2))
    with pytest.raises(ValueError, match="BatchResult: a pickled state of 17 fields"):
        pcr.BatchResult.__new__(pcr.BatchResult).__setstate__(())


def test_pose_is_a_sequence_and_an_array():
    pose = pcr.Pose(0.001, -0.002, 0.5)
    x, y, theta = pose
    assert (x, y, theta) == (0.001, -0.002, 0.5)
    assert len(pose) == 3 and pose[-1] == 0.5
    with pytest.raises(IndexError):
        pose[3]
    array = np.asarray(pose)
    assert array.dtype == np.float64 and array.tolist() == [0.001, -0.002, 0.5]
    assert np.asarray(pose, dtype=np.float32).dtype == np.float32
    assert np.allclose(np.array([pose, pose]), [[0.001, -0.002, 0.5]] * 2)


def test_batch_result_says_what_it_holds(robot):
    batch = robot.forward(np.array([[0.001, 0.0, 0.0], [0.5, 0.0, 0.0]]))
    assert repr(batch) == "<pcr.BatchResult 2 rows, 1 converged>"
