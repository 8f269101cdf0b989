"""pcr.study on a spatial robot: a tiny study end to end on a LocalCluster, its rows held to facts
the trial does not compute (the tracker's default noise from the rods' length, the nominal
geometry's error against the identified one, the counts of configurations), the attachment
tolerance drawn inside its scaled intervals, and the factors of the other kind refused."""
import math

import numpy as np
import pytest

import pcr

study = pytest.importorskip("pcr.study", reason="the [study] extra is not installed")
pd = pytest.importorskip("pandas")

# 2 trials: 2 levels x 1 replicate, few configurations and cycles (a trial about 1-2 s).
TINY = """
[study]
name = "tiny-spatial"
seed = 3
trials = 1

[factors]
robot = "continuum-stewart-gough"
calibration_count = 30
validation_count = 10
repeat = 2
noise_angle = 2e-6

[levels]
attachment_scale = [0.5, 2.0]
"""
ROD_LENGTH = 0.4  # m, every rod of the reference robot at q = 0


def test_a_tiny_spatial_study_runs_end_to_end(tmp_path):
    definition = study.Study.from_toml(TINY, "tiny.toml")
    table = study.run(definition, tmp_path / "out", workers=1, progress=False)
    assert len(table) == 2 and table["failure"].isna().all(), list(table["failure"])
    # The rows carry the factors the study set, and the defaults of the others.
    assert list(table["attachment_scale"]) == [0.5, 2.0]
    assert (table["robot"] == "continuum-stewart-gough").all()
    assert (table["calibration_count"] == 30).all() and (table["repeat"] == 2).all()
    assert (table["payload"] == 0.0).all() and table["mount_tolerance"].isna().all()

    # The noise: the paper's 9.13 nm scaled by 0.4 m / 30 mm, and the study's angle; the floor
    # of an rms error over three axes is sqrt(3) sigma.
    sigma = 9.13e-9 * ROD_LENGTH / 30e-3
    assert np.allclose(table["noise.position_m"], sigma, rtol=1e-9)
    assert np.allclose(table["noise.floor_position_m"], math.sqrt(3) * sigma, rtol=1e-9)
    assert np.allclose(table["noise.floor_angle_rad"], math.sqrt(3) * 2e-6, rtol=1e-12)

    # Every configuration measured or counted as not measurable.
    total = table["configurations.calibration"] + table["configurations.validation"] + \
        table["configurations.unreachable"]
    assert (total == 40).all()

    # After calibration the validation error (configurations the calibration never saw) is near
    # the floor, and far below the nominal geometry's, which grows with the tolerance.
    v = "table3.identified_model_validation_set"
    n = "table3.nominal_model_validation_set"
    print(table[[f"{v}.rms_position_m", f"{n}.rms_position_m", "noise.floor_position_m",
                 f"{v}.rms_angle_rad", "accuracy.helix.identified.ap_p.mean",
                 "accuracy.helix.nominal.ap_p.mean", "time_s"]].to_string())
    assert (table[f"{v}.rms_position_m"] < 3 * table["noise.floor_position_m"]).all()
    assert (table[f"{v}.rms_angle_rad"] < 3 * table["noise.floor_angle_rad"]).all()
    assert (table[f"{n}.rms_position_m"] > 10 * table[f"{v}.rms_position_m"]).all()
    assert table[f"{n}.rms_position_m"].iloc[1] > table[f"{n}.rms_position_m"].iloc[0]
    # Table 4: every path attained closer with the identified model than with the nominal one.
    for path in ("square", "circle", "helix"):
        assert (table[f"accuracy.{path}.identified.ap_p.max"] <
                0.2 * table[f"accuracy.{path}.nominal.ap_p.max"]).all(), path
    assert (table["time.calibration_s"] > 0).all()

    text = study.summary(tmp_path / "out")
    assert "2 trials, 0 failed" in text and "noise floor sqrt(3) sigma" in text
    written = study.plot(tmp_path / "out")
    assert all(p.endswith((".png", ".csv")) for p in written)


def test_the_attachment_scale_draws_the_truth_inside_the_scaled_intervals():
    nominal = pcr.SpatialRobot.reference()
    from pcr.study._trial import _with_attachment_scale

    for scale in (0.25, 4.0):
        truth = pcr.SpatialVirtualRobot(_with_attachment_scale(nominal, scale), seed=2).truth
        moved = np.array([np.concatenate([t.A - r.A, t.B - r.B])
                          for t, r in zip(truth.rods, nominal.rods)])
        # The reference robot's attachments are known to +-100 um; 36 uniform draws.
        assert np.abs(moved).max() <= scale * 100e-6 * (1 + 1e-9)
        assert np.abs(moved).max() > 0.5 * scale * 100e-6


@pytest.mark.parametrize("factors, message", [
    (dict(mount_tolerance=1e-4), "factor mount_tolerance = 0.0001 does not apply to the spatial"),
    (dict(load_force_x=1e-3), "factor load_force_x = 0.001 does not apply to the spatial"),
])
def test_planar_factors_are_refused_for_a_spatial_robot(tmp_path, factors, message):
    row = study.run_trial({"robot": "continuum-stewart-gough", **factors}, seed=1)
    assert message in row["failure"], row["failure"]
    definition = study.Study.from_dict({"factors": {"robot": "continuum-stewart-gough",
                                                    **factors}}, "mine.toml")
    with pytest.raises(ValueError, match=message):
        study.run(definition, tmp_path / "out", workers=1, progress=False)
    assert not (tmp_path / "out").exists()


def test_spatial_factors_are_refused_for_a_planar_robot():
    row = study.run_trial({"attachment_scale": 2.0}, seed=1)
    assert "factor attachment_scale = 2.0 does not apply to the planar robot" in row["failure"]
    row = study.run_trial({"payload": 0.01}, seed=1)
    assert "factor payload = 0.01 does not apply to the planar robot" in row["failure"]


def test_the_design_spatial_study_runs_both_designs_on_the_same_robots(tmp_path):
    """The built-in design-spatial study cut to one replicate of 20 configurations (2 trials):
    both designs run on the same truth, the D-optimal one chosen among its candidates, and both
    identify the robot far below the nominal geometry's error."""
    definition = study.Study.load("design-spatial")
    assert definition.levels == {"design": ["poisson-disc", "d-optimal"],
                                 "calibration_count": [20, 40, 60]}
    assert definition.trials == 20 and definition.factors["robot"] == "continuum-stewart-gough"
    tiny = definition.replace(trials=1, levels={**definition.levels, "calibration_count": [20]},
                              factors={**definition.factors, "validation_count": 10, "repeat": 2})
    table = study.run(tiny, tmp_path / "out", workers=1, progress=False)
    assert len(table) == 2 and table["failure"].isna().all(), list(table["failure"])
    assert list(table["design"]) == ["poisson-disc", "d-optimal"]
    # One replicate: one seed, so one truth and one tracker for both designs.
    assert table["seed"].nunique() == 1
    assert (table["configurations.calibration"] + table["configurations.unreachable"] >= 20).all()
    v = "table3.identified_model_validation_set"
    n = "table3.nominal_model_validation_set"
    print(table[["design", f"{v}.rms_position_m", f"{v}.rms_angle_rad", f"{n}.rms_position_m",
                 "calibration.jacobian_rank", "noise.floor_position_m", "time_s"]].to_string())
    assert (table[f"{n}.rms_position_m"] > 10 * table[f"{v}.rms_position_m"]).all()
