"""pcr.run_method: the method `pcr demo` runs, as one call. The demo and a Python run of the same
robot, seed and counts agree to the bit, and a study's trial is that call."""
import json
import subprocess

import numpy as np
import pytest

import pcr

pytestmark = pytest.mark.skipif(not pcr.has_calibration, reason="built without pcr::calib")


def test_the_demo_is_run_method(cli, tmp_path):
    out = tmp_path / "demo"
    subprocess.run([cli, "demo", "--no-vision", "--quiet", "--seed", "3", "--calibration", "30",
                    "--validation", "10", "--repeat", "2", "--poses", "6", "--output", str(out)],
                   check=True, capture_output=True)
    report = json.loads((out / "report.json").read_text())

    design = pcr.Robot.default()
    stages = []
    r = pcr.run_method(design, pcr.VirtualRobot(design, seed=3), count=30, validation_count=10,
                       seed=3, repeat=2, square_poses=6, circle_poses=6, on_stage=stages.append)
    assert stages == ["sensitivity", "sampling", "measurement", "calibration", "validation",
                      "accuracy", "maps"]
    assert r.calibration.to_dict(r.table)["table3"] == report["calibration"]["table3"]
    identified = pcr.Robot.load(out / "identified.json")
    assert np.array_equal(identified.parameters, r.identified.parameters)
    q, measured = pcr.read_dataset(out / "calibration.csv")
    assert np.array_equal(q, r.measured["calibration"][0])
    assert np.array_equal(measured, r.measured["calibration"][1])
    assert r.map["stable_area"] == report["workspace"]["stable_area_m2"]
    assert r.sensitivity["ranking"] == report["sensitivity"]["ranking"]
    assert r.selection.decision == report["calibration"]["model_selection"]["decision"]
    assert set(r.accuracy) == {(p, m) for p in ("square", "circle")
                               for m in ("nominal", "identified")}
    assert all(s >= 0 for s in r.seconds.values())


def test_run_method_names_a_bad_argument():
    design = pcr.Robot.default()
    robot = pcr.VirtualRobot(design, seed=1)
    with pytest.raises(ValueError, match="model"):
        pcr.run_method(design, robot, model="everything")
    with pytest.raises(ValueError, match="repeat"):
        pcr.run_method(design, robot, repeat=1)
    with pytest.raises(TypeError, match="not a CalibrationOptions field"):
        pcr.run_method(design, robot, drop_unreachables=True)
