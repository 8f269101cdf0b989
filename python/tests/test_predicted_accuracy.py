"""Predicted accuracy bindings: a calibration's covariance as a pcr.ParameterCovariance, the
report's covariance block read back (and refused when malformed), Robot.predicted_accuracy
against a small Monte Carlo of FK."""
import json

import numpy as np
import pytest

import pcr

pytestmark = pytest.mark.skipif(not pcr.has_calibration, reason="pcr::calib not built")


def uncertain_extrinsics_and_lengths(robot, length):
    nominal = robot.copy()
    u = pcr.Uncertainty()
    u.camera = robot.uncertainty.camera
    u.pattern = robot.uncertainty.pattern
    limbs = []
    for _ in range(3):
        limb = pcr.LimbUncertainty()
        limb.l = length
        limbs.append(limb)
    u.limbs = limbs
    nominal.uncertainty = u
    return nominal


def write_block(path, names, matrix):
    rows = [[None if np.isnan(v) else float(v) for v in row] for row in matrix]
    path.write_text(json.dumps({"covariance": {"parameters": list(names),
                                               "units": "SI, flat order", "matrix": rows}}))


def test_calibration_covariance_reads_back(robot, tmp_path):
    nominal = uncertain_extrinsics_and_lengths(robot, 126e-6)
    v = pcr.VirtualRobot(nominal, seed=5)
    q = pcr.sensitivity_configurations(nominal, 2e-3)
    stages = [{"name": "extrinsics", "free": ["extrinsics"]},
              {"name": "lengths", "free": ["l", "extrinsics"]}]
    _, result = pcr.calibrate(nominal, q, v.measure(q)["measured"], stages=stages)
    cov = result.covariance
    assert isinstance(cov, pcr.ParameterCovariance)
    assert cov.names == [p.name for p in result.parameters]
    assert cov.num_limbs == 3 and not cov.has_load
    std = np.array([p.std_dev for p in result.parameters])
    assert np.sqrt(np.diag(cov.matrix)) == pytest.approx(std, rel=1e-12, abs=0.0)

    path = tmp_path / "report.json"
    path.write_text(result.to_json())  # the report pcr_calibrate writes
    read = pcr.read_parameter_covariance(path, 3)
    assert read.names == cov.names
    assert np.array_equal(read.matrix, cov.matrix, equal_nan=True)

    bad = cov.matrix.copy()
    l0, l1 = cov.names.index("l[0]"), cov.names.index("l[1]")
    bad[l0, l1] *= 2  # no longer symmetric
    write_block(path, cov.names, bad)
    with pytest.raises(ValueError,
                       match=rf"report\.json.*covariance\.matrix\[{l0}\]\[{l1}\].*symmetric"):
        pcr.read_parameter_covariance(path)
    write_block(path, cov.names, cov.matrix)
    with pytest.raises(ValueError, match=r"covariance\.parameters: .* the robot has 2"):
        pcr.read_parameter_covariance(path, 2)
    with pytest.raises(FileNotFoundError):
        pcr.read_parameter_covariance(tmp_path / "missing.json")


def test_predicted_accuracy_matches_monte_carlo(robot):
    names = pcr.parameter_names(3)
    l0, ax1 = names.index("l[0]"), names.index("A_x[1]")
    sigma = np.array([3e-6, 2e-6])
    block = np.array([[1.0, 0.5], [0.5, 1.0]]) * np.outer(sigma, sigma)
    matrix = np.zeros((len(names), len(names)))
    matrix[np.ix_([l0, ax1], [l0, ax1])] = block
    cov = pcr.ParameterCovariance(names, matrix)

    q = np.array([2e-3, -1e-3, 1e-3])
    solution = robot.forward(q)
    a = robot.predicted_accuracy(solution, cov)
    assert a["ok"] and a["status"] == "ok"
    assert a["covariance"].shape == (3, 3)
    assert a["position_3sigma"] == pytest.approx(3 * a["position_1sigma"])

    # 400 draws: a standard deviation within ~3.5 % (1 sigma) of the true one; 15 % is safe and
    # still catches a factor of 2 on the covariance.
    rng = np.random.default_rng(3)
    draws = rng.multivariate_normal(np.zeros(2), block, size=400)
    poses = []
    for d in draws:
        r = robot.copy()
        r.limbs[0].l += d[0]
        r.limbs[1].A[0] += d[1]
        s = r.forward(q, warm_start=solution)
        assert s.converged
        poses.append(s.pose.to_array())
    sample = np.cov(np.array(poses).T)
    assert np.sqrt(np.linalg.eigvalsh(sample[:2, :2])[-1]) == pytest.approx(
        a["position_1sigma"], rel=0.15)
    assert np.sqrt(sample[2, 2]) == pytest.approx(a["orientation_1sigma"], rel=0.15)

    # A batch is the single prediction at each row.
    batch = robot.predicted_accuracy(np.array([q, [0.0, 0.0, 0.0]]), cov)
    assert batch["covariance"].shape == (2, 3, 3) and batch["ok"].tolist() == [True, True]
    assert batch["covariance"][0] == pytest.approx(a["covariance"], rel=1e-6)
    # The measurement's noise, added as given.
    measured = robot.predicted_accuracy(solution, cov, measurement_covariance=[1e-16, 1e-16, 1e-12])
    assert np.diag(measured["covariance"] - a["covariance"]) == pytest.approx(
        [1e-16, 1e-16, 1e-12], rel=1e-6)
    # Without a covariance: the worst case over the robot's intervals only.
    worst = robot.predicted_accuracy(solution)
    assert worst["status"] == "no_covariance" and not worst["ok"]
    assert np.isnan(worst["position_1sigma"])
    assert worst["worst_position"] > 0
    assert max(worst["worst_components"][:2]) <= worst["worst_position"] <= np.hypot(
        *worst["worst_components"][:2])
    # In the camera's frame, with the extrinsics' uncertainty: a camera offset adds its variance.
    cov_camera = matrix.copy()
    cov_camera[names.index("camera_x"), names.index("camera_x")] = (5e-6) ** 2
    in_camera = robot.predicted_accuracy(solution, pcr.ParameterCovariance(names, cov_camera),
                                         frame="measurement")
    assert np.trace(in_camera["covariance"][:2, :2]) == pytest.approx(
        np.trace(a["covariance"][:2, :2]) + (5e-6) ** 2, rel=1e-9)
    with pytest.raises(ValueError, match="frame"):
        robot.predicted_accuracy(solution, cov, frame="camera")
    with pytest.raises(ValueError, match="measurement_covariance"):
        robot.predicted_accuracy(solution, cov, measurement_covariance=[1.0, 2.0])
    with pytest.raises(ValueError, match=r"ParameterCovariance.*covariance\.parameters\[2\]"):
        pcr.ParameterCovariance(names[:2] + ["length[0]"] + names[3:], matrix)
