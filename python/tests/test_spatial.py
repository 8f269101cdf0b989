"""pcr.SpatialRobot: the spatial robot file through Python, FK/IK against `pcr fk`/`pcr ik` and
against each other, the rotation's three forms against closed forms (Rodrigues, the half-angle
quaternion), pickling, batches in any order, bad inputs, the 3-D plot."""
import copy
import csv
import io
import os
import pickle
import subprocess

import numpy as np
import pytest

import pcr
from test_kinematics import run_cli

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
SPATIAL_FILE = os.path.join(ROOT, "robots", "continuum-stewart-gough.json")
PLANAR_FILE = os.path.join(ROOT, "robots", "femto-3pf.json")

# Joints (m) of the reference robot: home, and rods lengthened and shortened by up to 2 cm (the
# platform rises, tilts and turns).
Q = np.array([[0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
              [0.01, 0.01, 0.01, 0.01, 0.01, 0.01],
              [0.02, -0.01, 0.005, 0.0, -0.015, 0.01],
              [-0.01, 0.015, 0.02, -0.005, 0.0, 0.01]])
JOINTS = ["q1", "q2", "q3", "q4", "q5", "q6"]
POSE_COLUMNS = ["x", "y", "z", "rx", "ry", "rz"]


@pytest.fixture(scope="module")
def spatial():
    return pcr.SpatialRobot.reference()


@pytest.fixture(scope="module")
def fk(spatial):
    """FK of the rows of Q, each on its own (with the rods' shapes)."""
    return spatial.forward(Q, shapes=True)


def rodrigues(v):
    """exp([v]x), the closed form: I + sin(a) K + (1 - cos(a)) K^2 (a = |v|, K of the axis)."""
    angle = np.linalg.norm(v)
    if angle == 0:
        return np.eye(3)
    x, y, z = v / angle
    K = np.array([[0, -z, y], [z, 0, -x], [-y, x, 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


def half_angle_quaternion(v):
    """(cos(a / 2), sin(a / 2) axis) of the rotation vector v."""
    angle = np.linalg.norm(v)
    axis = v / angle if angle > 0 else np.zeros(3)
    return np.concatenate([[np.cos(angle / 2)], np.sin(angle / 2) * axis])


def test_robot_load_gives_either_kind():
    robot = pcr.Robot.load(SPATIAL_FILE)
    assert isinstance(robot, pcr.SpatialRobot)
    assert robot.to_json() == pcr.SpatialRobot.reference().to_json()
    assert robot.name == "continuum-stewart-gough" and robot.num_rods == 6
    rod = robot.rods[0]
    assert rod.actuation == "length_through_hole" and rod.attachment == "clamped"
    assert (rod.length, rod.diameter, rod.young_modulus) == (0.4, 0.002, 200e9)
    assert np.hypot(*rod.A[:2]) == pytest.approx(0.087) and rod.A[2] == 0
    assert list(robot.gravity) == [0, 0, -9.81] and robot.platform_mass == 0.1
    assert isinstance(pcr.Robot.from_json(robot.to_json()), pcr.SpatialRobot)
    assert isinstance(pcr.Robot.load(PLANAR_FILE), pcr.Robot)  # planar files as before
    with pytest.raises(ValueError, match="femto-3pf.json"):
        pcr.SpatialRobot.load(PLANAR_FILE)
    assert repr(robot) == "<pcr.SpatialRobot 'continuum-stewart-gough' with 6 rods>"


def test_robot_edits_copies_files_and_pickles(tmp_path):
    robot = pcr.SpatialRobot()
    edited = robot.copy()
    edited.rods[2].length = 0.41  # a reference into the robot
    edited.gravity[2] = -9.8
    edited.rods[0].actuation = "translated_clamp"
    assert edited.rods[2].length == 0.41 and robot.rods[2].length == 0.4
    assert edited.rods[0].actuation == "translated_clamp"
    assert edited.replace(name="other").name == "other" and edited.name == robot.name
    path = tmp_path / "robot.json"
    edited.save(path)
    assert pcr.Robot.load(path).to_json() == edited.to_json()
    for other in (pickle.loads(pickle.dumps(edited)), copy.copy(edited), copy.deepcopy(edited)):
        assert other.to_json() == edited.to_json()
    limb = pickle.loads(pickle.dumps(edited.rods[2]))
    assert limb.length == 0.41 and list(limb.B) == list(edited.rods[2].B)
    fewer = robot.copy()
    fewer.rods = robot.rods[:5]
    assert fewer.num_rods == 5


def test_forward_and_inverse_round_trip(spatial, fk):
    assert fk.converged.all() and list(fk.status) == ["converged"] * len(Q)
    assert np.array_equal(fk.q, Q)
    # The platform rises with the rods all lengthened, and stays level by symmetry.
    assert fk.position[1, 2] - fk.position[0, 2] > 0.005
    assert np.linalg.norm(fk.rotation_vector[1]) < 1e-8
    for k in (2, 3):
        s = spatial.forward(Q[k])
        assert s.converged and s.stable and s.max_strain > 0 and s.rod_steps > 0
        assert s.residual_evaluations >= s.iterations > 0
        assert s.position_error_estimate < 1e-6 and s.angle_error_estimate < 1e-6
        ik = spatial.inverse(s.position, quaternion=s.quaternion)
        assert ik.converged
        assert ik.q == pytest.approx(Q[k], abs=1e-9)  # IK(FK(q)) = q
        assert ik.position == pytest.approx(s.position, abs=0)
        assert ik.wrenches == pytest.approx(s.wrenches, rel=1e-5, abs=1e-7)
        # The same pose as a matrix or a rotation vector: the same joints.
        by_matrix = spatial.inverse(s.position, rotation=s.rotation)
        by_vector = spatial.inverse(s.position, rotation_vector=s.rotation_vector)
        assert by_matrix.q == pytest.approx(ik.q, abs=1e-10)
        assert by_vector.q == pytest.approx(ik.q, abs=1e-10)


@pytest.mark.parametrize("rods", [[0, 2, 4], [0, 1, 2, 3, 4]])
def test_inverse_of_three_and_five_rods_solves_the_free_orientation(spatial, rods):
    """Three rods impose the position, five also the platform's normal: IK of FK's pose gives back
    the joints and solves the rest of the orientation (FK's), whatever rotation is passed for it."""
    robot = spatial.copy()
    robot.rods = [spatial.rods[i] for i in rods]
    q = np.array([0.01, -0.005, 0.008, 0.0, 0.004])[: len(rods)]
    s = robot.forward(q)
    assert s.converged
    # A turn of the free part: about the platform's z axis for five rods, any for three.
    twist = rodrigues(np.array([0.0, 0.0, 0.3] if len(rods) == 5 else [0.2, -0.1, 0.3]))
    ik = robot.inverse(s.position, rotation=s.rotation @ twist)  # the free part turned away
    assert ik.converged
    assert ik.q == pytest.approx(q, abs=1e-9)
    assert ik.position == pytest.approx(s.position, abs=0)
    assert ik.rotation == pytest.approx(s.rotation, abs=1e-8)
    batch = robot.inverse(np.array([s.position]), rotation=np.array([s.rotation @ twist]))
    assert batch.rotation[0] == pytest.approx(s.rotation, abs=1e-8)  # the solved one, not echoed


def test_rotation_forms_agree_with_closed_forms(fk):
    for k in range(len(Q)):
        R, h, v = fk.rotation[k], fk.quaternion[k], fk.rotation_vector[k]
        assert R.T @ R == pytest.approx(np.eye(3), abs=1e-14) and np.linalg.det(R) > 0
        assert np.linalg.norm(h) == pytest.approx(1, abs=1e-15) and h[0] >= 0  # (w, x, y, z)
        assert rodrigues(v) == pytest.approx(R, abs=1e-14)
        assert half_angle_quaternion(v) == pytest.approx(h, abs=1e-14)
    assert np.abs(fk.rotation_vector[2:]).max() > 1e-3  # the tilted rows do turn


def test_shapes_end_on_the_platform(spatial, fk):
    accuracy = pcr.SolverOptions().position_accuracy
    for k in range(len(Q)):
        shapes = fk.shapes[k]
        assert len(shapes) == 6
        for rod, shape in zip(spatial.rods, shapes):
            assert shape.shape == (fk.rod_steps[k] + 1, 8)
            assert shape[0, 1:4] == pytest.approx(rod.A, abs=1e-15)  # leaves its hole
            tip = fk.position[k] + fk.rotation[k] @ rod.B
            # ends at its attachment, within what the solver promises
            assert shape[-1, 1:4] == pytest.approx(tip, abs=accuracy)
    lengths = [shape[-1, 0] for shape in fk.shapes[2]]
    assert lengths == pytest.approx(0.4 + Q[2], abs=1e-15)


def test_agrees_with_cli(cli, spatial, fk):
    rows = run_cli(cli, "fk", Q, JOINTS, "--robot", SPATIAL_FILE)
    for k, row in enumerate(rows):
        assert row["status"] == fk.status[k] == "converged"
        assert fk.position[k] == pytest.approx([float(row[c]) for c in "xyz"], abs=1e-12)
        # the CLI's rx, ry, rz are Python's rotation_vector: one convention
        assert fk.rotation_vector[k] == pytest.approx(
            [float(row[c]) for c in ("rx", "ry", "rz")], abs=1e-12)
        assert fk.max_strain[k] == pytest.approx(float(row["max_strain"]), rel=1e-9)
    poses = np.array([[float(row[c]) for c in POSE_COLUMNS] for row in rows[1:]])
    ik_rows = run_cli(cli, "ik", poses, POSE_COLUMNS, "--robot", SPATIAL_FILE)
    ik = spatial.inverse(poses[:, :3], rotation_vector=poses[:, 3:])
    for k, row in enumerate(ik_rows):
        assert row["status"] == ik.status[k] == "converged"
        assert ik.q[k] == pytest.approx([float(row[q]) for q in JOINTS], abs=1e-12)
        assert ik.q[k] == pytest.approx(Q[k + 1], abs=1e-9)
        assert ik.rotation_vector[k] == pytest.approx(poses[k, 3:], abs=1e-15)  # echoed


def test_batches_in_any_order_match_single_solves(spatial, fk):
    order = np.random.default_rng(5).permutation(len(Q))
    shuffled = spatial.forward_batch(Q[order])
    assert np.array_equal(shuffled.position, fk.position[order])
    assert np.array_equal(shuffled.quaternion, fk.quaternion[order])
    for k in range(len(Q)):
        single = spatial.forward(Q[k])
        assert np.array_equal(single.position, fk.position[k])
        assert np.array_equal(single.wrenches, fk.wrenches[k])
    ik = spatial.inverse_batch(fk.position[order], quaternion=fk.quaternion[order])
    assert ik.converged.all() and ik.q == pytest.approx(Q[order], abs=1e-9)
    single = spatial.inverse(fk.position[order[0]], quaternion=fk.quaternion[order[0]])
    assert np.array_equal(single.q, ik.q[0])
    # One orientation for many positions (broadcast), and a path.
    level = spatial.inverse(fk.position[:2], rotation=np.eye(3))
    assert level.q == pytest.approx(Q[:2], abs=1e-9)
    path = spatial.forward(np.linspace(Q[0], Q[2], 4), path=True)
    assert path.converged.all() and path.position[-1] == pytest.approx(fk.position[2], abs=1e-8)


def test_warm_starts(spatial, fk):
    cold = spatial.forward(Q[2])
    near = spatial.forward(Q[2] + 1e-4)
    warm = spatial.forward(Q[2] + 1e-4, warm_start=cold)
    assert warm.converged and warm.position == pytest.approx(near.position, abs=1e-9)
    assert warm.residual_evaluations < near.residual_evaluations
    # from an unpickled solution (no factorised Jacobian) and from IK
    again = spatial.forward(Q[2] + 1e-4, warm_start=pickle.loads(pickle.dumps(cold)))
    assert again.position == pytest.approx(near.position, abs=1e-9)
    ik = spatial.inverse(fk.position[2], quaternion=fk.quaternion[2], warm_start=cold)
    ik2 = spatial.inverse(fk.position[2] + [0, 0, 1e-4], quaternion=fk.quaternion[2],
                          warm_start=ik)
    assert ik.converged and ik2.converged and ik.q == pytest.approx(Q[2], abs=1e-9)


def test_solutions_and_batches_pickle(spatial, fk):
    s = spatial.forward(Q[3], shapes=True)
    for other in (pickle.loads(pickle.dumps(s)), copy.copy(s), copy.deepcopy(s)):
        assert np.array_equal(other.q, s.q) and np.array_equal(other.quaternion, s.quaternion)
        assert np.array_equal(other.wrenches, s.wrenches) and other.status == s.status
        assert (other.iterations, other.residual_evaluations, other.rod_steps) == (
            s.iterations, s.residual_evaluations, s.rod_steps)
        assert other.stability_margin == s.stability_margin
        assert all(np.array_equal(a, b) for a, b in zip(other.shapes, s.shapes))
    back = pickle.loads(pickle.dumps(fk))
    assert isinstance(back, pcr.SpatialBatchResult) and len(back) == len(Q)
    for name in ("q", "position", "quaternion", "rotation", "rotation_vector", "wrenches",
                 "status", "iterations", "max_strain", "stability_margin"):
        assert np.array_equal(getattr(back, name), getattr(fk, name)), name
    assert repr(back) == f"<pcr.SpatialBatchResult {len(Q)} rows, {len(Q)} converged>"
    with pytest.raises(ValueError, match="SpatialSolution: not a pickled one"):
        pcr.SpatialSolution.__new__(pcr.SpatialSolution).__setstate__((1, 2))
    with pytest.raises(ValueError, match="SpatialBatchResult: a pickled state of 20 fields"):
        pcr.SpatialBatchResult.__new__(pcr.SpatialBatchResult).__setstate__(())


def test_bad_inputs_say_what_they_got(spatial):
    p = [0.0, 0.0, 0.4]
    cases = [
        (lambda: spatial.forward([0.0] * 5), r"q: expected 6 numbers.*got 5 numbers"),
        (lambda: spatial.forward([0.0] * 5 + [float("nan")]), r"q: non-finite value nan"),
        (lambda: spatial.inverse([0.0, 0.4]), r"position: expected 3 numbers.*got 2 numbers"),
        (lambda: spatial.inverse(p, quaternion=[1, 0, 0, 0.1]),
         r"quaternion: expected a quaternion.*unit norm.*got \(1, 0, 0, 0.1\), of norm 1.00"),
        (lambda: spatial.inverse(p, quaternion=[1, 0, 0]),
         r"quaternion: expected 4 numbers.*got 3 numbers \(1, 0, 0\)"),
        (lambda: spatial.inverse(p, rotation=np.diag([1.0, 1.0, 1.1])),
         r"rotation: expected a rotation matrix.*got \(1, 0, 0, 0, 1, 0, 0, 0, 1.1\)"),
        (lambda: spatial.inverse(p, rotation=np.diag([1.0, 1.0, -1.0])),
         r"rotation: .*det R = -1"),
        (lambda: spatial.inverse(p, rotation=[1.0, 0.0, 0.0]),
         r"rotation: expected a \(3, 3\) rotation matrix.*got 3 numbers"),
        (lambda: spatial.inverse(p, rotation_vector=[0.0, float("inf"), 0.0]),
         r"rotation_vector: non-finite value inf"),
        (lambda: spatial.inverse(p, quaternion=[1, 0, 0, 0], rotation=np.eye(3)),
         r"orientation is given once"),
        (lambda: spatial.inverse([p, p], quaternion=[[1, 0, 0, 0]] * 3),
         r"2 positions and 3 orientations"),
        (lambda: spatial.inverse_batch(p), r"expected an \(N, 3\) array"),
    ]
    for call, message in cases:
        with pytest.raises(ValueError, match=message):
            call()
    limb = spatial.copy().rods[0]
    with pytest.raises(ValueError, match=r"SpatialLimb.base_orientation: .*\(1, 0, 0, 0.1\)"):
        limb.base_orientation = [1, 0, 0, 0.1]
    with pytest.raises(ValueError, match=r"SpatialLimb.actuation: .*got 'pulled'"):
        limb.actuation = "pulled"
    four = spatial.copy()
    four.rods = spatial.rods[:4]
    assert four.inverse(p).status == "unsupported"  # the solver's verdict, not an exception
    with pytest.raises(ValueError, match="warm_start: a solution of a robot with 6 rods"):
        four.forward([0.0] * 4, warm_start=spatial.home())


def test_workspace_map_slice_matches_fk_and_the_cli(cli, spatial):
    """A 3 x 3 x-y slice around home: every point reachable, FK of its joints at its pose, and the
    joints `pcr map` writes for the same slice (stdout: the rows in the same order)."""
    span = (-0.01, 0.01, -0.01, 0.01)
    m = pcr.workspace_map(spatial, plane="xy", range=span, grid=3, threads=1)
    assert m["plane"] == "xy" and m["q"].shape == (3, 3, 6) and m["poses"].shape == (3, 3, 6)
    assert m["u"] == pytest.approx([-0.01, 0.0, 0.01]) and m["reachable"].all()
    assert m["reachable_area"] == pytest.approx(9 * 0.01 * 0.01)  # points times a cell
    for iv in range(3):
        for iu in range(3):
            pose = m["poses"][iv, iu]
            assert pose[0] == pytest.approx(m["u"][iu]) and pose[1] == pytest.approx(m["v"][iv])
            s = spatial.forward(m["q"][iv, iu])
            assert s.position == pytest.approx(pose[:3], abs=1e-9)
            assert s.rotation_vector == pytest.approx(pose[3:], abs=1e-8)
    out = subprocess.run([cli, "map", "--robot", SPATIAL_FILE, "--grid", "3", "--range",
                          ",".join(repr(v) for v in span), "--threads", "1"],
                         capture_output=True, text=True, check=True, timeout=120)
    rows = list(csv.DictReader(io.StringIO(out.stdout)))
    assert len(rows) == 9
    for k, row in enumerate(rows):
        assert m["q"][k // 3, k % 3] == pytest.approx([float(row[q]) for q in JOINTS], abs=1e-12)
    with pytest.raises(ValueError, match="plane"):
        pcr.workspace_map(spatial, plane="xw")


def test_plot_robot_draws_in_3d(spatial, fk, tmp_path):
    import matplotlib
    matplotlib.use("Agg")
    import pcr.plot

    fig = pcr.plot.plot_robot(SPATIAL_FILE, Q[2], path=tmp_path / "one.png")
    assert fig.axes[0].name == "3d" and (tmp_path / "one.png").stat().st_size > 1000
    solutions = [spatial.forward(q, shapes=True) for q in Q[:2]]
    fig = pcr.plot.plot_robot(spatial, solutions)
    assert fig.axes[0].name == "3d"
    assert len(fig.axes[0].lines) >= 12  # six rods per configuration
    from matplotlib.figure import Figure
    with pytest.raises(ValueError, match="3-D axes"):
        pcr.plot.plot_robot(spatial, Q[0], ax=Figure().add_subplot())
