"""Robot.forward / Robot.inverse: agreement with the `pcr fk` / `pcr ik` CLI, batched vs looped,
geometric checks (rod tips on the platform's clamps, IK(FK(q)) = q), bad inputs."""
import csv
import io
import math
import subprocess

import numpy as np
import pytest

import pcr

Q = np.array([[0.0, 0.0, 0.0],
              [0.002, -0.001, 0.0005],
              [0.004, 0.003, -0.002],
              [-0.006, 0.001, 0.003],
              [0.008, -0.007, 0.002]])


def run_cli(cli, command, rows, header, *extra):
    text = ",".join(header) + "\n" + "".join(",".join(repr(float(v)) for v in r) + "\n" for r in rows)
    out = subprocess.run([cli, command, *extra], input=text, capture_output=True, text=True,
                         check=False, timeout=120)
    assert out.returncode in (0, 1), out.stderr
    return list(csv.DictReader(io.StringIO(out.stdout)))


def test_forward_agrees_with_cli(cli, robot):
    rows = run_cli(cli, "fk", Q, ["q1", "q2", "q3"])
    batch = robot.forward(Q)
    for k, row in enumerate(rows):
        assert row["status"] == batch.status[k] == "converged"
        expected = [float(row["x"]), float(row["y"]), float(row["theta"])]
        assert batch.pose[k] == pytest.approx(expected, abs=1e-12)
        assert batch.max_strain[k] == pytest.approx(float(row["max_strain"]), rel=1e-6, abs=1e-12)
    # single calls from home against one-row CLI runs (cold starts on both sides)
    single = robot.forward(Q[2])
    (row,) = run_cli(cli, "fk", Q[2:3], ["q1", "q2", "q3"])
    assert single.converged and single.status == "converged"
    assert single.pose.to_array() == pytest.approx(
        [float(row["x"]), float(row["y"]), float(row["theta"])], abs=1e-12)


def test_forward_with_external_load_agrees_with_cli(cli, robot):
    rows = run_cli(cli, "fk", Q[1:3], ["q1", "q2", "q3"], "--force", "0.005,-0.002", "--moment",
                   "1e-5")
    batch = robot.forward(Q[1:3], force=(0.005, -0.002), moment=1e-5)
    unloaded = robot.forward(Q[1:3])
    for k, row in enumerate(rows):
        expected = [float(row["x"]), float(row["y"]), float(row["theta"])]
        assert batch.pose[k] == pytest.approx(expected, abs=1e-12)
        # the load moves the platform by much more than the tolerance
        assert np.max(np.abs(batch.pose[k] - unloaded.pose[k])) > 1e-8


def test_inverse_agrees_with_cli(cli, robot):
    poses = robot.forward(Q).pose
    rows = run_cli(cli, "ik", poses, ["x", "y", "theta"])
    batch = robot.inverse(poses)
    for k, row in enumerate(rows):
        assert row["status"] == batch.status[k] == "converged"
        assert batch.q[k] == pytest.approx([float(row[f"q{i}"]) for i in (1, 2, 3)], abs=1e-12)
        assert batch.q[k] == pytest.approx(Q[k], abs=1e-9)  # IK(FK(q)) = q
    single = robot.inverse(pcr.Pose(*poses[4]))
    assert single.q == pytest.approx(Q[4], abs=1e-9)
    assert robot.inverse(poses[4]).q == pytest.approx(single.q, abs=0)


def test_batched_equals_looped(robot):
    rng = np.random.default_rng(3)
    q = np.cumsum(rng.uniform(-1e-3, 1e-3, size=(12, 3)), axis=0)
    batch = robot.forward(q, path=True)  # a path: each row warm-started from the one before
    previous = None
    for k in range(len(q)):
        s = robot.forward(q[k], warm_start=previous)
        previous = s if s.converged else None
        assert batch.status[k] == s.status
        assert batch.iterations[k] == s.iterations
        assert batch.pose[k] == pytest.approx(s.pose.to_array(), abs=0)
        assert batch.wrenches[k] == pytest.approx(s.wrenches, abs=0)
    poses = batch.pose
    ik = robot.inverse(poses, path=True)
    previous = None
    for k in range(len(q)):
        s = robot.inverse(poses[k], warm_start=previous)
        previous = s if s.status in ("converged", "out_of_range") else None
        assert ik.status[k] == s.status
        assert ik.q[k] == pytest.approx(s.q, abs=0)


def test_shapes_end_on_the_platform_clamps(robot):
    s = robot.forward(Q[4], shapes=True)
    assert len(s.shapes) == 3
    c, sn = math.cos(s.pose.theta), math.sin(s.pose.theta)
    for limb, shape, q in zip(robot.limbs, s.shapes, Q[4]):
        assert shape.shape == (s.rod_steps + 1, 4)
        direction = np.array([math.cos(limb.alpha + limb.gamma), math.sin(limb.alpha + limb.gamma)])
        assert shape[0, 1:3] == pytest.approx(limb.A + q * direction, abs=1e-15)
        assert shape[-1, 0] == pytest.approx(limb.l)
        tip = [s.pose.x + c * limb.B[0] - sn * limb.B[1], s.pose.y + sn * limb.B[0] + c * limb.B[1]]
        assert shape[-1, 1:3] == pytest.approx(tip, abs=1e-9)  # closure: rod tip = B_i in W
        assert shape[-1, 3] == pytest.approx(s.pose.theta + limb.beta, abs=1e-9)
    batch = robot.forward(Q[:2], shapes=True)
    assert len(batch.shapes) == 2 and len(batch.shapes[1]) == 3
    assert robot.forward(Q[4]).shapes is None


def test_home_is_the_origin(robot):
    home = robot.home()
    assert home.converged
    assert home.pose.to_array() == pytest.approx([0, 0, 0], abs=1e-15)
    assert home.wrenches == pytest.approx(np.zeros((3, 3)), abs=1e-12)


def test_failures_are_statuses_not_exceptions(robot):
    out = robot.inverse(np.array([[0.0, 0.0, 0.0], [0.5, 0.0, 0.0], [0.001, 0.0, 0.0]]))
    assert list(out.converged) == [True, False, True]
    assert np.isnan(out.q[1]).all() and out.status[1] != "converged"
    assert out.pose[1, :2] == pytest.approx([0.5, 0.0])


def test_bad_inputs_raise(robot):
    with pytest.raises(ValueError, match=r"q: expected 3 numbers.*, got 2 numbers \(0, 0\)"):
        robot.forward([0.0, 0.0])
    with pytest.raises(ValueError, match=r"got an array of shape \(4, 2\)"):
        robot.forward(np.zeros((4, 2)))
    with pytest.raises(ValueError, match="non-finite"):
        robot.forward([0.0, float("nan"), 0.0])
    with pytest.raises(ValueError, match="pose"):
        robot.inverse("abc")
    with pytest.raises(ValueError, match="force"):
        robot.forward([0, 0, 0], force=(float("inf"), 0))
    with pytest.raises(TypeError):
        robot.forward([0, 0, 0], shapes="yes", options=3)
    six = robot.copy()
    six.limbs = list(robot.limbs) * 2
    with pytest.raises(ValueError, match="more than 3 limbs"):
        six.inverse([0, 0, 0])


def test_one_stroke_verdict_for_every_caller(cli, robot):
    """The solver decides the stroke: `pcr fk`, Robot.forward (rows and single), the sampler's
    admissible_configuration and the calibration's warning give the same verdict, row by row, on
    rows drawn at random inside and just outside the strokes, in no order."""
    rng = np.random.default_rng(29)
    lo = np.array([limb.q_range[0] for limb in robot.limbs])
    hi = np.array([limb.q_range[1] for limb in robot.limbs])
    q = rng.uniform(lo - 0.05 * (hi - lo), hi + 0.05 * (hi - lo), size=(60, 3))
    outside = ((q < lo) | (q > hi)).any(axis=1)

    rows = run_cli(cli, "fk", q, ["q1", "q2", "q3"])
    cli_status = np.array([row["status"] for row in rows])
    batch = robot.forward(q)
    assert list(batch.status) == list(cli_status)
    assert [row["converged"] for row in rows] == ["1" if c else "0" for c in batch.converged]
    # Where the robot has an equilibrium (not everywhere in the box: some rows lie past a fold),
    # its status is the stroke's verdict.
    equilibrium = np.isin(cli_status, ["converged", "out_of_range"])
    assert (equilibrium & outside).sum() >= 5 and (equilibrium & ~outside).sum() >= 10
    expected = np.where(outside, "out_of_range", "converged")
    assert list(cli_status[equilibrium]) == list(expected[equilibrium])
    assert list(batch.converged) == list(equilibrium & ~outside)
    for k in rng.permutation(len(q))[:8]:
        single = robot.forward(q[k])
        assert single.status == cli_status[k]
        if equilibrium[k]:
            assert single.pose.to_array() == pytest.approx(batch.pose[k], abs=1e-12)
    for k in np.flatnonzero(equilibrium & outside):  # the sampler never admits them
        assert not pcr.admissible_configuration(robot, q[k])

    # The calibration fits every row with an equilibrium and warns of those outside the stroke.
    fit = np.flatnonzero(equilibrium)
    measured = pcr.VirtualRobot(robot, seed=3, noise_position=0.0,
                                noise_angle=0.0).measure_dataset(q[fit])
    fit = fit[measured["ok"]]
    _, result = pcr.calibrate(robot, q[fit], measured["measured"][measured["ok"]],
                              stages=[{"name": "ext", "free": ["extrinsics"]}],
                              compute_covariance=False)
    warning = [w for w in result.warnings if "outside the stroke" in w]
    assert len(warning) == 1
    assert warning[0].startswith(f"{outside[fit].sum()} rows have joints outside the stroke")
    assert result.dropped == []


def test_precurved_rods_reach_the_cli_and_the_file(cli, robot, tmp_path):
    # Rods shape-set to arcs and clothoids (Limb.precurvature, 1/m; precurvature_slope, 1/m^2):
    # Python, the saved file and `pcr fk` on it give one answer.
    curved = robot.copy()
    curved.limbs = [limb.replace(precurvature=u0, precurvature_slope=u1)
                    for limb, (u0, u1) in zip(robot.limbs, [(12.0, 0.0), (-8.0, 500.0), (0.0, -700.0)])]
    assert "precurvature=-8" in repr(curved.limbs[1]) and "precurvature" not in repr(robot.limbs[0])
    path = tmp_path / "curved.json"
    curved.save(path)
    loaded = pcr.Robot.load(path)
    assert [(l.precurvature, l.precurvature_slope) for l in loaded.limbs] == \
        [(12.0, 0.0), (-8.0, 500.0), (0.0, -700.0)]
    rng = np.random.default_rng(11)
    q = rng.uniform(-0.006, 0.006, size=(6, 3))
    rows = run_cli(cli, "fk", q, ["q1", "q2", "q3"], "--robot", str(path))
    batch = curved.forward(q)
    for k, row in enumerate(rows):
        assert row["status"] == batch.status[k] == "converged"
        assert batch.pose[k] == pytest.approx([float(row[c]) for c in ("x", "y", "theta")],
                                              abs=1e-12)


def test_tapered_rods_reach_the_cli_and_the_file(cli, robot, tmp_path):
    # Tapered rods (Limb.diameter_slope, m/m: d(s) = d + diameter_slope s): Python, the saved file
    # and `pcr fk` on it give one answer, and a thinner tip bends the robot differently.
    slopes = [limb.d * (ratio - 1.0) / limb.l for limb, ratio in zip(robot.limbs, (0.6, 1.0, 1.5))]
    tapered = robot.copy()
    tapered.limbs = [limb.replace(diameter_slope=k) for limb, k in zip(robot.limbs, slopes)]
    assert "diameter_slope=" in repr(tapered.limbs[0]) and "diameter_slope" not in repr(robot.limbs[0])
    path = tmp_path / "tapered.json"
    tapered.save(path)
    assert [l.diameter_slope for l in pcr.Robot.load(path).limbs] == slopes
    q = np.random.default_rng(13).uniform(-0.006, 0.006, size=(6, 3))
    rows = run_cli(cli, "fk", q, ["q1", "q2", "q3"], "--robot", str(path))
    batch, uniform = tapered.forward(q), robot.forward(q)
    for k, row in enumerate(rows):
        assert row["status"] == batch.status[k] == "converged"
        assert batch.pose[k] == pytest.approx([float(row[c]) for c in ("x", "y", "theta")],
                                              abs=1e-12)
    assert np.abs(batch.pose - uniform.pose).max() > 1e-7
    slopes[0] = -0.7 * robot.limbs[0].d / robot.limbs[0].l  # the tip at 0.3 d: refused on load
    tapered.limbs = [limb.replace(diameter_slope=k) for limb, k in zip(robot.limbs, slopes)]
    with pytest.raises(ValueError, match=r"limbs\[0\]\.diameter_slope"):
        tapered.save(tmp_path / "too-thin.json")


def test_rods_shape_set_to_arcs_act_as_a_moment_on_the_platform(robot):
    # theta' = m / EI + u0 is theta' = (m + EI u0) / EI: rods shape-set to arcs and clamped at both
    # ends are straight rods whose moment carries EI u0 more, so the platform sits where the straight
    # robot's does under the moment sum EI_i u0_i, at every joint value (to the solver's accuracy).
    curved = robot.copy()
    curved.limbs = [limb.replace(precurvature=u0) for limb, u0 in zip(robot.limbs, (12.0, -8.0, 5.0))]
    moment = sum(limb.EI * limb.precurvature for limb in curved.limbs)
    q = np.random.default_rng(12).uniform(-0.006, 0.006, size=(12, 3))
    arcs, loaded, straight = curved.forward(q), robot.forward(q, moment=moment), robot.forward(q)
    assert list(arcs.status) == list(loaded.status)  # the same folds, too
    solved = arcs.status == "converged"
    assert solved.sum() >= 8
    np.testing.assert_allclose(arcs.pose[solved, :2], loaded.pose[solved, :2], rtol=0, atol=2e-9)
    np.testing.assert_allclose(arcs.pose[solved, 2], loaded.pose[solved, 2], rtol=0, atol=2e-6)
    assert np.abs(arcs.pose[solved] - straight.pose[solved]).max() > 1e-7  # the moment moves it
