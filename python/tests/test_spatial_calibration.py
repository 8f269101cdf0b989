"""Spatial calibration bindings: pcr.calibrate_spatial on a virtual spatial robot's measurements
(pcr.simulate_spatial_measurements), the result's fields with the C++ parameter names, the report
pcr_calibrate writes, and bad inputs."""
import json
import math

import numpy as np
import pytest

import pcr

pytestmark = pytest.mark.skipif(not pcr.has_calibration, reason="pcr::calib not built")

# The extrinsics alone: a few seconds, while the default stages take ~15 s (tests/
# test_pcr_calibrate_spatial.cpp scores those against the noise floor).
EXTRINSICS = [{"name": "extrinsics", "free": ["extrinsics"], "bounds_scale": 1.0}]


@pytest.fixture(scope="module")
def measured():
    nominal = pcr.SpatialRobot.reference()
    q = np.random.default_rng(3).uniform(0.0, 0.01, (24, 6))  # joints in [0, 10] mm
    simulated = pcr.simulate_spatial_measurements(nominal, q, seed=5)
    ok = simulated["ok"]
    assert ok.sum() >= 20
    return nominal, q[ok], simulated["measured"][ok], simulated


def test_simulated_measurements_have_the_dataset_columns(measured):
    nominal, q, poses, simulated = measured
    assert poses.shape == (len(q), 6)
    assert isinstance(simulated["truth"], pcr.SpatialRobot)
    # The noise is of the declared size: measured less exact, well under 10 sigma per row.
    exact = simulated["exact"][simulated["ok"]]
    worst = np.abs(poses[:, :3] - exact[:, :3]).max()
    print(f"worst position noise {worst:.3g} m, sigma {simulated['noise_position']:.3g} m")
    assert 0 < worst < 10 * simulated["noise_position"]


def test_calibrate_spatial_returns_the_results_fields(measured):
    nominal, q, poses, _ = measured
    identified, result = pcr.calibrate_spatial(nominal, q[:16], poses[:16], q[16:], poses[16:],
                                               stages=EXTRINSICS)
    assert isinstance(identified, pcr.SpatialRobot)
    names = [p["name"] for p in result["parameters"]]
    assert len(names) == 16 * 6 + 12
    assert names[:2] == ["E[0]", "G[0]"] and "l[5]" in names and names[-1] == "marker_rz"
    free = {p["name"] for p in result["parameters"] if p["free"]}
    assert free == {p + a for p in ("tracker_", "marker_") for a in ("x", "y", "z", "rx", "ry",
                                                                      "rz")}
    assert [s["name"] for s in result["stages"]] == ["extrinsics"]
    assert result["free_count"] == 12 and result["jacobian_rank"] <= 12
    assert math.isfinite(result["orientation_weight"]) and result["orientation_weight"] > 0
    report = json.loads(result["report_json"])
    assert report["kind"] == "spatial"
    errors = report["pose_errors"]
    nominal_mean = errors["nominal_model_calibration_set"]["e_p_m"]["mean"]
    print(f"extrinsics only: rms {result['rms_position']:.3g} m (nominal mean e_p "
          f"{nominal_mean:.3g} m), validation rms {result['validation_rms_position']:.3g} m")
    # With the extrinsics alone free, the identified model is the report's nominal model (the
    # nominal geometry with its extrinsics fitted). The tracker's and the marker's 1 mm / 50 mrad
    # errors (some 20 mm at the platform) are taken out; the rods' (tens of um) are not.
    identified_mean = errors["identified_model_calibration_set"]["e_p_m"]["mean"]
    assert identified_mean == pytest.approx(nominal_mean, rel=1e-9)
    assert 1e-6 < result["rms_position"] < 1e-3
    assert errors["identified_model_validation_set"]["configurations"] == len(q) - 16
    assert "pose errors" in result["report"] and "stages:" in result["report"]


def test_calibrate_spatial_refuses_bad_inputs(measured):
    nominal, q, poses, _ = measured
    with pytest.raises(ValueError, match="measured"):
        pcr.calibrate_spatial(nominal, q, poses[:, :3], stages=EXTRINSICS)
    with pytest.raises(ValueError, match="theta"):  # a planar kind
        pcr.calibrate_spatial(nominal, q, poses, stages=[{"name": "x", "free": ["theta"]}])
    with pytest.raises(ValueError, match="validation"):
        pcr.calibrate_spatial(nominal, q, poses, q, stages=EXTRINSICS)


def test_run_spatial_method_is_the_steps_one_by_one():
    """pcr.run_spatial_method against its steps through the other bindings: the truth is the one
    simulate_spatial_measurements draws from the same seed, and calibrating the measured sets
    with calibrate_spatial gives the method's Table 3."""
    nominal = pcr.SpatialRobot.reference()
    robot = pcr.SpatialVirtualRobot(nominal, seed=4)
    stages = []
    method = pcr.run_spatial_method(nominal, robot, count=30, validation_count=10, seed=4,
                                    stages=EXTRINSICS, repeat=2, square_poses=4, circle_poses=4,
                                    helix_poses=4, sensitivity=False, on_stage=stages.append)
    assert stages == ["sampling", "measurement", "calibration", "validation", "accuracy"]
    drawn = pcr.simulate_spatial_measurements(nominal, np.zeros((1, 6)), seed=4)["truth"]
    assert method.truth.to_json() == drawn.to_json() == robot.truth.to_json()
    q, poses = method.measured["calibration"]
    vq, vposes = method.measured["validation"]
    assert poses.shape == (len(q), 6) and len(q) + len(vq) + method.unmeasured == 40
    _, again = pcr.calibrate_spatial(nominal, q, poses, vq, vposes, stages=EXTRINSICS)
    for key in ("rms_position", "validation_rms_position", "validation_rms_angle"):
        assert method.calibration[key] == pytest.approx(again[key], rel=1e-9), key
    assert set(method.accuracy) == {(p, m) for p in ("square", "circle", "helix")
                                    for m in ("nominal", "identified")}
    helix = method.accuracy[("helix", "identified")]
    assert len(helix["poses"]) == 4 and helix["ap_p"]["max"] >= helix["ap_p"]["mean"] > 0
    assert method.seconds["calibration"] > 0 and method.seconds["sensitivity"] == 0
    with pytest.raises(ValueError, match="helix.num_poses"):
        pcr.run_spatial_method(nominal, robot, helix_poses=0)


def test_calibrate_spatial_names_outliers_and_drops_unreachable_rows(measured):
    """The planar calibration's options on a spatial robot: drop_unreachable leaves out (and
    names) a row without an equilibrium on the nominal robot, which is otherwise a ValueError; a
    row measured 1 mm off is named an outlier."""
    nominal, q, poses, _ = measured
    poses = poses.copy()
    poses[3, 1] += 1e-3
    far = np.vstack([q, np.full((1, 6), -0.39)])  # rods 1 cm long: no equilibrium
    far_poses = np.vstack([poses, poses[-1:]])
    with pytest.raises(ValueError, match=f"row {len(far)}: the nominal robot has no equilibrium"):
        pcr.calibrate_spatial(nominal, far, far_poses, stages=EXTRINSICS)
    _, result = pcr.calibrate_spatial(nominal, far, far_poses, stages=EXTRINSICS,
                                      drop_unreachable=True)
    assert len(result["dropped"]) == 1 and result["dropped"][0].startswith(f"row {len(far)} (")
    assert any("drop_unreachable" in w for w in result["warnings"])
    # The extrinsics alone leave the rods' errors (tens of um): the Huber scale follows the rows'
    # median up (beyond 5 noise units), and the 1 mm row stands out beyond it.
    print("outliers:", result["outliers"], "threshold", result["outlier_threshold"])
    assert "row 4" in [o.split(" (")[0] for o in result["outliers"]]
    assert len(result["outliers"]) < len(q) // 2
    assert result["outlier_threshold"] > 5.0
    assert result["residuals_exceed_noise"]  # the geometry is not fitted
    report = json.loads(result["report_json"])
    assert report["outlier_rows"] == result["outliers"]
    assert report["dropped_rows"] == result["dropped"]


def test_calibrate_selecting_model_takes_a_spatial_robot(measured):
    """pcr.calibrate_selecting_model on a SpatialRobot: the extrinsics alone leave residuals
    beyond the noise, so the load model (the last stage also frees the platform wrench) is fitted
    and tested on the validation rows; the results are calibrate_spatial's dicts."""
    nominal, q, poses, _ = measured
    identified, chosen, stages, load, selection = pcr.calibrate_selecting_model(
        nominal, q[:16], poses[:16], q[16:], poses[16:], stages=EXTRINSICS)
    assert isinstance(identified, pcr.SpatialRobot)
    assert isinstance(selection, pcr.SpatialModelSelection)
    print(selection.decision)
    assert stages["residuals_exceed_noise"] and selection.tried_load
    assert not stages["load_identified"] and load["load_identified"]
    assert selection.rows == len(q) - 16
    assert chosen["load_identified"] == selection.load_chosen
    assert ("load model" if selection.load_chosen else "stages' model") in selection.decision
