"""Calibration bindings: sensitivity, Jacobian vs finite differences, virtual robot vs FK of its
truth, datasets, Poisson-disc sampling and D-optimal design, a small identification."""
import json
import math
import subprocess

import numpy as np
import pytest

import pcr

pytestmark = pytest.mark.skipif(not pcr.has_calibration, reason="pcr::calib not built")


def test_sensitivity_table_shape(robot):
    report = pcr.sensitivity(robot)
    assert report["configurations"].shape == (26, 3)  # 3^3 grid minus its centre
    assert [r["param"] for r in report["table"]][:2] == ["E", "D"]
    assert sorted(report["ranking"]) == sorted(r["param"] for r in report["table"])
    first = next(r for r in report["table"] if r["param"] == report["ranking"][0])
    assert all(first["position_error_m"] >= r["position_error_m"] for r in report["table"])
    assert "alpha" in report["text"]


def test_sensitivity_report_is_the_one_the_cli_writes(cli, robot, tmp_path):
    """One serialiser: Python's report and `pcr sensitivity --json` have the same fields and
    values."""
    subprocess.run([cli, "sensitivity", "--step", "2e-3", "--json", str(tmp_path / "s.json")],
                   check=True, capture_output=True, timeout=120)
    written = json.loads((tmp_path / "s.json").read_text())
    report = pcr.sensitivity(robot, step=2e-3)
    assert set(report) == set(written) | {"text"}
    assert report["configurations"].tolist() == written["configurations"]
    assert report["table"] == written["table"] and report["ranking"] == written["ranking"]
    assert report["step_m"] == written["step_m"] == 2e-3


def test_parameter_jacobian_matches_finite_differences(robot):
    q = np.array([0.002, -0.001, 0.0005])
    jac = pcr.platform_parameter_jacobian(robot, q)
    names = pcr.parameter_names(3)
    assert jac.shape == (3, len(names) - 6)  # the limbs' columns, in parameter_names order
    # central differences of FK on l[0], A_y[1], alpha[2]
    for name, attr, limb, h in (("l[0]", "l", 0, 1e-7), ("A_y[1]", "A", 1, 1e-7),
                                ("alpha[2]", "alpha", 2, 1e-6)):
        index = names.index(name)
        poses = []
        for sign in (1, -1):
            r = robot.copy()
            if attr == "A":
                r.limbs[limb].A[1] += sign * h
            else:
                setattr(r.limbs[limb], attr, getattr(r.limbs[limb], attr) + sign * h)
            poses.append(r.forward(q).pose.to_array())
        fd = (poses[0] - poses[1]) / (2 * h)
        assert jac[:, index] == pytest.approx(fd, rel=1e-4, abs=1e-6 * np.max(np.abs(fd)))


def test_virtual_robot_measures_fk_of_its_truth(robot):
    v = pcr.VirtualRobot(robot, seed=4, noise_position=0.0, noise_angle=0.0)
    truth = v.truth
    assert truth.limbs[0].l != robot.limbs[0].l  # drawn inside the interval
    assert abs(truth.limbs[0].l - robot.limbs[0].l) <= robot.uncertainty.limbs[0].l
    q = np.array([[0.001, 0.002, -0.001], [0.003, -0.002, 0.0]])
    m = v.measure(q)
    assert m["ok"].all()
    fk = truth.forward(q)
    assert m["platform"] == pytest.approx(fk.pose, abs=1e-12)
    ext = truth.extrinsics
    for k in range(2):
        expected = ext.measurement_from_platform(pcr.Pose(*fk.pose[k])).to_array()
        assert m["measured"][k] == pytest.approx(expected, abs=1e-12)
    single = v.measure(q[0])
    assert single["ok"] and isinstance(single["measured"], pcr.Pose)


def test_measure_dataset_starts_from_home():
    # A tour after which the truth of seed 6 reaches the last row on another equilibrium than the
    # one connected to home (tests/test_calibration.cpp, ARowTheRobotReachedOnAnotherBranch...),
    # past the point where it stops being stable: the virtual robot does not measure it, and
    # measures the next row from home.
    tour = np.array([[3.6e-3, 1.5e-3, -10.2e-3], [6.0e-3, 1.5e-3, -1.6e-3]])
    v = pcr.VirtualRobot(pcr.Robot.default(), seed=6, noise_position=0.0, noise_angle=0.0)
    m = v.measure(tour)
    assert m["ok"].tolist() == [True, False] and m["status"][1] == "unstable"
    home_again = v.measure(tour[1])
    assert home_again["ok"]
    assert home_again["platform"].to_array() == pytest.approx(
        v.truth.forward(tour[1]).pose.to_array(), abs=1e-12)
    # Held there (the stability check off, as a guided robot would be):
    unchecked = pcr.SolverOptions()
    unchecked.check_stability = False
    v = pcr.VirtualRobot(pcr.Robot.default(), seed=6, noise_position=0.0, noise_angle=0.0,
                         options=unchecked)
    moved = v.measure(tour)["platform"]
    cold = v.truth.forward(tour[1]).pose.to_array()
    assert np.hypot(*(moved[1][:2] - cold[:2])) > 1e-3  # the setting: the tour snapped
    again = v.measure(tour[1])["platform"].to_array()  # continued: stays where it is
    assert again == pytest.approx(moved[1], abs=1e-12)
    alone = v.measure_dataset(tour[1:])["platform"][0]  # from home
    assert alone == pytest.approx(cold, abs=1e-12)
    assert v.measure_dataset(tour)["platform"] == pytest.approx(moved, abs=1e-12)


def test_noise_has_the_requested_size(robot):
    v = pcr.VirtualRobot(robot, seed=2, noise_position=1e-6, noise_angle=1e-5)
    q = np.tile([0.001, 0.0, -0.001], (200, 1))
    m = v.measure(q)
    assert np.std(m["measured"][:, 0] - m["exact"][:, 0]) == pytest.approx(1e-6, rel=0.2)
    assert np.std(m["measured"][:, 2] - m["exact"][:, 2]) == pytest.approx(1e-5, rel=0.2)


def test_dataset_round_trip_and_errors(tmp_path):
    q = np.array([[0.001, 0.002, 0.003], [-1e-3, 1.0 / 3.0 * 1e-3, 0.0]])
    measured = np.array([[1e-4, 2e-4, 0.01], [math.pi * 1e-5, -1e-6, -0.02]])
    path = str(tmp_path / "data.csv")
    pcr.write_dataset(path, q, measured)
    q2, m2 = pcr.read_dataset(path)
    assert np.array_equal(q2, q) and np.array_equal(m2, measured)
    (tmp_path / "bad.csv").write_text("q1,q2,q3,x,y,theta\n0,0,0,0,0,0\n0,abc,0,0,0,0\n")
    with pytest.raises(ValueError, match=r"bad\.csv:3:2"):
        pcr.read_dataset(str(tmp_path / "bad.csv"))
    with pytest.raises(ValueError, match="measured"):
        pcr.write_dataset(path, q, measured[:1])
    pcr.write_configurations(str(tmp_path / "q.csv"), q)
    assert np.array_equal(pcr.read_configurations(str(tmp_path / "q.csv")), q)


def test_poisson_disc_sample_spacing(robot):
    out = pcr.poisson_disc_sample(robot, count=12, seed=5, box_min=[-2e-3] * 3,
                                  box_max=[2e-3] * 3)
    q = out["configurations"]
    assert q.shape == (12, 3) and out["complete"]
    assert (q >= -2e-3).all() and (q <= 2e-3).all()
    d = np.linalg.norm(q[:, None, :] - q[None, :, :], axis=-1)
    assert d[~np.eye(12, dtype=bool)].min() >= out["min_distance"] * (1 - 1e-12)
    assert pcr.admissible_configuration(robot, q[0])
    with pytest.raises(ValueError):
        pcr.poisson_disc_sample(robot, count=0)


def test_d_optimal_sample(robot):
    box = dict(box_min=[-3e-3] * 3, box_max=[3e-3] * 3, seed=2)
    spread = pcr.sample_configurations(robot, count=6, validation_count=3, **box)
    out = pcr.sample_configurations(robot, count=6, validation_count=3, design="d-optimal",
                                    candidates=30, **box)
    assert out["design"] == "d-optimal" and out["calibration"].shape == (6, 3)
    assert np.array_equal(out["validation"], spread["validation"])  # the same Poisson-disc set
    chosen = out["candidates"]["configurations"][out["selected"]]
    assert np.array_equal(chosen, out["calibration"])
    assert out["rank"] <= out["dimension"] < out["parameters"]
    with pytest.raises(ValueError, match="d_optimal"):
        pcr.sample_configurations(robot, count=6, design="d_optimal")


def uncertain_extrinsics_and_lengths(robot, length=0.0):
    """A copy of robot whose only uncertain parameters are the extrinsics and (length > 0, in m)
    the rod lengths."""
    nominal = robot.copy()
    u = pcr.Uncertainty()
    u.camera = robot.uncertainty.camera
    u.pattern = robot.uncertainty.pattern
    u.limbs = [pcr.LimbUncertainty() for _ in range(3)]
    for limb in u.limbs:
        limb.l = length
    nominal.uncertainty = u
    return nominal


def test_calibration_recovers_extrinsics(robot):
    # A nominal whose only uncertain parameters are the extrinsics: the virtual robot's truth then
    # differs from it by its extrinsics only, and the extrinsics stage alone must explain the data.
    nominal = uncertain_extrinsics_and_lengths(robot)
    v_ext = pcr.VirtualRobot(nominal, seed=7, noise_position=0.0, noise_angle=0.0)
    assert v_ext.truth.limbs[0].l == nominal.limbs[0].l
    assert v_ext.truth.extrinsics.camera.x != 0.0
    q = pcr.sensitivity_configurations(nominal, 2e-3)[:10]
    measured = v_ext.measure(q)["measured"]
    lines = []
    identified, result = pcr.calibrate(
        nominal, q, measured, stages=[{"name": "ext", "free": ["extrinsics"]}],
        compute_covariance=False, fix_gauge=False, progress=lines.append)
    assert result.stages[0].name == "ext" and result.stages[0].usable
    assert result.stages[0].final_cost < result.stages[0].initial_cost
    assert result.covariance is None
    assert result.identified.to_json() == identified.to_json()
    truth = v_ext.truth
    # with a fixed robot, the camera-pattern pair is only known up to its combined effect
    # on the measurement: compare predictions instead of the parameters themselves
    e_p, e_t = pcr.pose_errors_per_configuration(identified, q, measured)
    e_nominal, _ = pcr.pose_errors_per_configuration(nominal, q, measured)
    assert np.max(e_p) < 1e-9 and np.max(e_nominal) > 1e-5
    stats = pcr.pose_errors(identified, q, measured)
    assert stats["count"] == 10
    assert stats["max_p"] == pytest.approx(np.max(e_p), rel=1e-6, abs=1e-15)
    assert stats["mean_theta"] == pytest.approx(np.mean(e_t), rel=1e-6, abs=1e-15)
    assert truth.name == nominal.name
    assert lines and all(isinstance(line, str) for line in lines)

    def broken(line):
        raise KeyError("from progress")

    with pytest.raises(KeyError, match="from progress"):
        pcr.calibrate(nominal, q, measured, stages=[{"name": "ext", "free": ["extrinsics"]}],
                      compute_covariance=False, progress=broken)
    with pytest.raises(ValueError, match="kind|unknown"):
        pcr.calibrate(nominal, q, measured, stages=[{"name": "x", "free": ["lenght"]}])
    with pytest.raises(ValueError, match="measured"):
        pcr.calibrate(nominal, q, measured[:3])
    # A row a metre off has no solution on the nominal geometry: named, or left out and listed.
    q_mm = np.array(q, copy=True)
    q_mm[3, 0] += 1.0  # 1 m: a unit slip
    with pytest.raises(ValueError, match="configuration 4 .* outside|configuration 4"):
        pcr.calibrate(nominal, q_mm, measured, stages=[{"name": "ext", "free": ["extrinsics"]}])
    _, result = pcr.calibrate(nominal, q_mm, measured, drop_unreachable=True,
                              stages=[{"name": "ext", "free": ["extrinsics"]}],
                              compute_covariance=False)
    assert len(result.dropped) == 1 and result.dropped[0].startswith("configuration 4 ")
    assert any("outside the stroke" in w for w in result.warnings)
    assert result.outliers == [] and result.unidentifiable == []


def test_calibration_identifies_a_platform_load(robot):
    # Lengths and extrinsics uncertain, a 1.8 mN force and 10 uN m on the platform: with the kind
    # "load" in the last stage the report gives the load within 4 of its standard deviations of
    # the truth's (no gauge moves it: neither the clamps nor the diameters are free), and FK under
    # it reproduces the noise-free measurements.
    nominal = uncertain_extrinsics_and_lengths(robot, 126e-6)
    v = pcr.VirtualRobot(nominal, seed=5, force=(1.5e-3, -1e-3), moment=1e-5)
    sets = pcr.sample_configurations(nominal, count=30, validation_count=10, seed=6)
    q, q_validation = sets["calibration"], sets["validation"]
    stages = [{"name": "extrinsics", "free": ["extrinsics"]},
              {"name": "lengths", "free": ["l", "camera", "pattern", "load"]}]
    identified, result = pcr.calibrate(nominal, q, v.measure(q)["measured"], stages=stages)
    assert result.load_identified
    std = {p.name: p.std_dev for p in result.parameters}
    fx, fy, mz = result.load
    assert fx == pytest.approx(1.5e-3, abs=4 * std["load_f_x"])
    assert fy == pytest.approx(-1e-3, abs=4 * std["load_f_y"])
    assert mz == pytest.approx(1e-5, abs=4 * std["load_m_z"])
    exact = v.measure(q_validation)["exact"]
    loaded = pcr.pose_errors(identified, q_validation, exact, force=(fx, fy), moment=mz)
    unloaded = pcr.pose_errors(identified, q_validation, exact)
    assert loaded["mean_p"] < 0.05e-6 < unloaded["mean_p"]


def test_pose_errors_per_configuration_follow_eqs_5_8_9(robot):
    """e_p and e_theta against Eq. 5 written with homogeneous matrices, on FK along the rows."""
    def matrix(pose):
        x, y, theta = pose
        c, s = math.cos(theta), math.sin(theta)
        return np.array([[c, -s, x], [s, c, y], [0.0, 0.0, 1.0]])

    q = pcr.sensitivity_configurations(robot, 2e-3)[::3]
    v = pcr.VirtualRobot(robot, seed=8, noise_position=1e-6, noise_angle=1e-5)
    measured = v.measure_dataset(q)["measured"]
    e_p, e_t = pcr.pose_errors_per_configuration(robot, q, measured)
    fk = robot.forward(q, path=True)
    camera = robot.extrinsics.camera.to_array()
    pattern = robot.extrinsics.pattern.to_array()
    for k in range(len(q)):
        w = matrix(camera) @ matrix(measured[k]) @ matrix(pattern)
        assert e_p[k] == pytest.approx(np.hypot(*(fk.pose[k, :2] - w[:2, 2])), rel=1e-9,
                                       abs=1e-15)
        d = fk.pose[k, 2] - math.atan2(w[1, 0], w[0, 0])
        assert e_t[k] == pytest.approx(abs(math.atan2(math.sin(d), math.cos(d))), rel=1e-9,
                                       abs=1e-15)
    assert e_p.max() > 1e-6  # the truth differs from the nominal robot
