"""The identification's classes: CalibrationOptions (the C++ defaults, checked fields, value
semantics, calibrate's keyword changes), CalibrationResult and CalibrationTable, and the report
they write, which is pcr_calibrate's."""
import copy
import json
import math
import os
import pickle
import subprocess

import numpy as np
import pytest

import pcr

pytestmark = pytest.mark.skipif(not pcr.has_calibration, reason="pcr::calib not built")


@pytest.fixture(scope="module")
def data():
    """A virtual robot's calibration and validation sets (the paper's noise)."""
    robot = pcr.Robot.default()
    v = pcr.VirtualRobot(robot, seed=3)
    sets = pcr.sample_configurations(robot, count=20, validation_count=10, seed=4)
    q, q_validation = sets["calibration"], sets["validation"]
    return robot, q, v.measure(q)["measured"], q_validation, v.measure(q_validation)["measured"]


def _state(options):
    """Every read-write property of a CalibrationOptions, fk as its own properties."""
    out = {}
    for name in dir(pcr.CalibrationOptions):
        if isinstance(getattr(pcr.CalibrationOptions, name), property):
            value = getattr(options, name)
            if isinstance(value, pcr.SolverOptions):
                value = {k: getattr(value, k) for k in dir(value) if not k.startswith("_") and
                         not callable(getattr(value, k))}
            out[name] = value
    return out


def _without_times(report):
    """The report less what the clock decides (each stage's time_s)."""
    report = copy.deepcopy(report)
    for stage in report["stages"]:
        del stage["time_s"]
    return report


def test_default_options_are_the_cpp_defaults(data):
    robot, q, measured, _, _ = data
    options = pcr.CalibrationOptions()
    assert options.stages == pcr.default_stages()
    assert options.derivatives == "implicit" and options.stage_gauge == "subspace"
    # None, a default CalibrationOptions and every field given again by name: the same
    # identification (the report but for the clock).
    explicit = {name: getattr(options, name) for name in _state(options)}
    reports = []
    for args, changes in (((), {}), ((options,), {}), ((), explicit)):
        _, result = pcr.calibrate(robot, q, measured, *args, **changes)
        reports.append(_without_times(result.to_dict()))
    assert reports[1] == reports[0] and reports[2] == reports[0]


def test_options_pickle_and_copy_to_an_equal_value(tmp_path):
    options = pcr.CalibrationOptions().replace(
        stages=[{"name": "ext", "free": ["extrinsics"]},
                {"name": "lengths", "free": ["l", "extrinsics"], "bounds_scale": 2.0}],
        orientation_weight=0.01, residual_scale=1e-8, derivatives="numeric", max_iterations=17,
        fix_gauge=False, gauge_prior_weight=0.5, stage_gauge="prior", function_tolerance=1e-8,
        intermediate_function_tolerance=1e-3, compute_covariance=False, robust_scale=0.0,
        drop_unreachable=True)
    options.fk.max_iterations = 23  # fk is a reference into the options
    expected = _state(options)
    assert expected["fk"]["max_iterations"] == 23 and expected["stages"][1]["bounds_scale"] == 2
    for twin in (pickle.loads(pickle.dumps(options)), copy.copy(options), copy.deepcopy(options)):
        assert type(twin) is pcr.CalibrationOptions
        assert _state(twin) == expected
    other = copy.copy(options)
    other.max_iterations = 3
    other.fk.max_iterations = 4
    assert options.max_iterations == 17 and options.fk.max_iterations == 23
    # The stages may come from a file, read when assigned.
    path = tmp_path / "stages.json"
    path.write_text(json.dumps({"stages": expected["stages"]}))
    assert pcr.CalibrationOptions().replace(stages=path).stages == expected["stages"]


def test_calibrate_changes_a_copy_of_the_options(data):
    robot, q, measured, _, _ = data
    options = pcr.CalibrationOptions().replace(stages=[{"name": "ext", "free": ["extrinsics"]}])
    _, result = pcr.calibrate(robot, q, measured, options, compute_covariance=False)
    assert options.compute_covariance  # unchanged
    assert [s.name for s in result.stages] == ["ext"] and result.covariance is None
    _, result = pcr.calibrate(robot, q, measured, options)
    assert isinstance(result.covariance, pcr.ParameterCovariance)


def test_an_unknown_option_is_a_type_error_naming_it(data):
    robot, q, measured, _, _ = data
    with pytest.raises(TypeError, match="unexpected keyword argument 'stage'"):
        pcr.calibrate(robot, q, measured, stage=pcr.default_stages())
    with pytest.raises(TypeError, match="'replace'"):  # a method, not a field
        pcr.calibrate(robot, q, measured, replace=None)
    with pytest.raises(AttributeError, match="stage"):
        pcr.CalibrationOptions().replace(stage=[])


@pytest.mark.parametrize("field, value, message", [
    ("orientation_weight", -1.0, r"orientation_weight: expected a number from 0 to 10 \(m/rad\), "
                                 r"got -1"),
    ("residual_scale", 0.0, r"residual_scale: expected a number from 1e-15 to 1 \(m\), got 0"),
    ("residual_scale", math.nan, r"residual_scale: .* got nan"),
    ("derivatives", "exact", r"derivatives: expected 'implicit', 'numeric' or 'autodiff', "
                             r"got 'exact'"),
    ("max_iterations", 0, r"max_iterations: expected a number from 1 to 100000, got 0"),
    ("gauge_prior_weight", -0.5, r"gauge_prior_weight: .* got -0.5"),
    ("stage_gauge", "weak", r"stage_gauge: expected 'subspace' or 'prior', got 'weak'"),
    ("function_tolerance", 2.0, r"function_tolerance: expected a number from 0 to 1, got 2"),
    ("robust_scale", math.inf, r"robust_scale: .* got inf"),
    ("stages", [{"name": "x", "free": ["lenght"]}], r"stages\[0\]\.free: unknown kind \"lenght\""),
    ("stages", [{"name": "x"}], r"stages\[0\]\.free: missing required field"),
    ("stages", [{"free": "l"}], r"stages\[0\]\.free: expected a list of kinds \(str\), got 'l'"),
    ("stages", [{"free": ["l"], "bounds_scale": 0}], r"stages\[0\]\.bounds_scale"),
    ("stages", [["l"]], r"stages\[0\]: expected a dict"),
    ("stages", 3, r"stages: expected a list of dicts .* got a single number 3"),
    ("stages", [], r"stages: no stage"),
])
def test_a_bad_value_is_a_value_error_naming_the_field(data, field, value, message):
    robot, q, measured, _, _ = data
    options = pcr.CalibrationOptions()
    before = _state(options)
    with pytest.raises(ValueError, match=message):
        setattr(options, field, value)
    assert repr(_state(options)) == repr(before)  # refused, not half set
    with pytest.raises(ValueError, match=message):
        pcr.calibrate(robot, q, measured, **{field: value})


def test_result_and_table(data):
    robot, q, measured, q_validation, measured_validation = data
    identified, result = pcr.calibrate(robot, q, measured)
    assert result.identified.to_json() == identified.to_json()
    assert identified.uncertainty is not None  # the nominal's section, kept
    # The paper's nominal model: the nominal geometry, the identified extrinsics.
    nominal_model = result.extrinsics_only
    assert [l.l for l in nominal_model.limbs] == [l.l for l in robot.limbs]
    assert nominal_model.extrinsics.camera.x != robot.extrinsics.camera.x
    names = pcr.parameter_names(3)
    assert [p.name for p in result.parameters] == names
    l1 = result.parameters[names.index("l[1]")]
    assert l1.kind == "l" and l1.free and l1.identifiable and l1.std_dev > 0
    assert l1.value == identified.limbs[1].l and l1.nominal == robot.limbs[1].l
    assert [s.name for s in result.stages] == [s["name"] for s in pcr.default_stages()]
    assert all(s.usable and s.final_cost <= s.initial_cost for s in result.stages)
    assert sum(g.present for g in result.gauge) == 7
    assert result.free_count - result.jacobian_rank == 7
    assert result.singular_values.shape == (result.free_count,)
    assert 0.5 < result.residual_variance < 2 and result.covariance_ok
    assert result.load == (0.0, 0.0, 0.0) and not result.load_identified
    assert result.dropped == result.outliers == result.unidentifiable == result.warnings == []

    table = pcr.calibration_table(result, q, measured, q_validation, measured_validation)
    assert table.has_validation and table.warnings == []
    for stats, model, rows in ((table.nominal_calibration, nominal_model, (q, measured)),
                               (table.identified_calibration, identified, (q, measured)),
                               (table.identified_validation, identified,
                                (q_validation, measured_validation))):
        expected = pcr.pose_errors(model, *rows)
        assert {k: getattr(stats, k) for k in expected} == pytest.approx(expected, rel=1e-9)
    assert table.identified_validation.mean_p < 0.1e-6 < table.nominal_validation.mean_p
    alone = pcr.calibration_table(result, q, measured)
    assert not alone.has_validation and alone.nominal_validation is None
    # Without a table the report's Table 3 is the calibration set's.
    assert result.to_dict() == json.loads(result.to_json(alone))
    assert "validation set" in result.to_text(table) and "validation" not in alone.to_text()
    with pytest.raises(ValueError, match="validation_q and validation_measured"):
        pcr.calibration_table(result, q, measured, q_validation)
    with pytest.raises(ValueError, match=r"validation_measured: expected an \(N, 3\) array"):
        pcr.calibration_table(result, q, measured, q_validation, measured_validation[:4])


def _assert_same_json(actual, expected, where="report"):
    """Equal JSON values, numbers within the last printed digit."""
    if isinstance(expected, dict):
        assert isinstance(actual, dict) and list(actual) == list(expected), where
        for key in expected:
            _assert_same_json(actual[key], expected[key], f"{where}.{key}")
    elif isinstance(expected, list):
        assert isinstance(actual, list) and len(actual) == len(expected), where
        for k, (a, e) in enumerate(zip(actual, expected)):
            _assert_same_json(a, e, f"{where}[{k}]")
    elif isinstance(expected, float) and not isinstance(actual, bool):
        assert actual == pytest.approx(expected, rel=1e-12, abs=0.0), where
    else:
        assert actual == expected, where


def test_report_is_the_one_pcr_calibrate_writes(data, cli, tmp_path):
    program = os.path.join(os.path.dirname(os.path.abspath(cli)), "pcr_calibrate")
    if not os.access(program, os.X_OK):
        pytest.skip(f"{program} was not found (built with pcr::calib)")
    robot, q, measured, q_validation, measured_validation = data
    robot.save(tmp_path / "nominal.json")
    pcr.write_dataset(tmp_path / "cal.csv", q, measured)
    pcr.write_dataset(tmp_path / "val.csv", q_validation, measured_validation)

    def report(*validation):
        subprocess.run([program, "--robot", "nominal.json", "--data", "cal.csv", *validation,
                        "--output", "identified.json", "--report", "report.json", "--quiet"],
                       cwd=tmp_path, check=True, capture_output=True)
        written = json.loads((tmp_path / "report.json").read_text())
        assert written.pop("inputs")["data"] == "cal.csv"  # pcr_calibrate's own addition
        return _without_times(written)

    identified, result = pcr.calibrate(robot, q, measured)  # the default options
    # Without a table: Table 3 on the calibration set, as pcr_calibrate without --validation.
    _assert_same_json(_without_times(result.to_dict()), report())
    table = pcr.calibration_table(result, q, measured, q_validation, measured_validation)
    written = report("--validation", "val.csv")
    _assert_same_json(_without_times(result.to_dict(table)), written)
    assert "covariance" in written and "nominal_model_validation_set" in written["table3"]
    cli_identified = pcr.Robot.load(tmp_path / "identified.json")
    assert np.allclose([[l.l, *l.A, l.alpha, *l.B] for l in cli_identified.limbs],
                       [[l.l, *l.A, l.alpha, *l.B] for l in identified.limbs], rtol=1e-12, atol=0)


def _calibrate_in_worker(args):
    robot, q, measured, options = args
    return pcr.calibrate(robot, q, measured, options)


def test_results_pickle_and_cross_process_boundaries(data):
    # What Dask and multiprocessing do: the options go to a worker process by pickle, and the
    # identified robot and the result come back, the same as this process's.
    import concurrent.futures
    import multiprocessing
    robot, q, measured, q_validation, measured_validation = data
    options = pcr.CalibrationOptions().replace(robust_scale=0.0)
    identified, result = pcr.calibrate(robot, q, measured, options)
    table = pcr.calibration_table(result, q, measured, q_validation, measured_validation)
    expected = result.to_json(table)
    for twin in (pickle.loads(pickle.dumps(result)), copy.copy(result), copy.deepcopy(result)):
        assert type(twin) is pcr.CalibrationResult
        assert twin.to_json(table) == expected
        assert twin.to_json() == result.to_json()  # the calibration set came along
        assert twin.identified.to_json() == identified.to_json()
        assert twin.extrinsics_only.to_json() == result.extrinsics_only.to_json()
        assert np.array_equal(twin.singular_values, result.singular_values)
        assert [p.kind for p in twin.parameters] == [p.kind for p in result.parameters]
    for twin in (pickle.loads(pickle.dumps(table)), copy.deepcopy(table)):
        assert result.to_json(twin) == expected and twin.to_text() == table.to_text()
    with concurrent.futures.ProcessPoolExecutor(
            1, mp_context=multiprocessing.get_context("spawn")) as pool:
        remote_identified, remote = pool.submit(_calibrate_in_worker,
                                                (robot, q, measured, options)).result()
    assert remote_identified.to_json() == identified.to_json()
    assert _without_times(remote.to_dict(table)) == _without_times(result.to_dict(table))
    with pytest.raises(ValueError, match="CalibrationResult: a pickled state of 7 fields"):
        pcr.CalibrationResult.__new__(pcr.CalibrationResult).__setstate__(())


def test_in_gauge_moves_the_truth_to_the_identified_frames():
    """Without noise, the identified parameters equal the truth's once it is moved to the frames
    the calibration fixed (limb 0's references); the truth as drawn differs by the gauge, and the
    moved truth predicts the same measurements."""
    nominal = pcr.Robot.default()
    v = pcr.VirtualRobot(nominal, seed=9, noise_position=0.0, noise_angle=0.0)
    q = pcr.sample_configurations(nominal, count=60, seed=2)["calibration"]
    _, result = pcr.calibrate(nominal, q, v.measure(q)["measured"])
    moved = result.in_gauge(v.truth)
    names = pcr.parameter_names(3)
    identified = {p.name: p.value for p in result.parameters}

    def values(robot):
        return dict(zip(names, robot.parameters))

    truth, moved_values = values(v.truth), values(moved)
    for name in ("A_x[0]", "A_y[0]", "alpha[0]", "B_x[0]", "B_y[0]", "beta[0]"):
        assert moved_values[name] == pytest.approx(values(nominal)[name], abs=1e-12)
    for name in ("A_x[1]", "B_y[2]", "l[1]", "camera_x", "pattern_y"):
        assert abs(identified[name] - moved_values[name]) < 2e-7, name
    assert max(abs(identified[n] - truth[n]) for n in ("A_x[1]", "A_y[2]", "camera_x")) > 1e-5
    for row in q[:5]:
        a = v.truth.extrinsics.measurement_from_platform(v.truth.forward(row).pose)
        b = moved.extrinsics.measurement_from_platform(moved.forward(row).pose)
        assert np.allclose(np.asarray(a), np.asarray(b), atol=1e-11)
    with pytest.raises(ValueError, match="expected 3 limbs"):
        result.in_gauge(pcr.Robot.from_json(nominal.to_json()).replace(
            limbs=list(nominal.limbs)[:2]))


def test_robot_parameters_are_in_parameter_names_order():
    robot = pcr.Robot.default().with_limb(2, l=0.0311, A=(0.01, -0.02), gamma=1e-3)
    ext = robot.extrinsics
    ext.pattern = pcr.Pose(1e-3, 2e-3, 0.03)
    robot.extrinsics = ext
    values = dict(zip(pcr.parameter_names(3), robot.parameters))
    assert len(robot.parameters) == len(values) == 39
    assert values["l[2]"] == 0.0311 and values["A_x[2]"] == 0.01 and values["A_y[2]"] == -0.02
    assert values["gamma[2]"] == 1e-3 and values["E[1]"] == robot.limbs[1].E
    assert values["d[0]"] == robot.limbs[0].d and values["beta[1]"] == robot.limbs[1].beta
    assert (values["pattern_x"], values["pattern_y"], values["pattern_theta"]) == (1e-3, 2e-3, 0.03)
    # The calibration's nominal values are the same vector.
    default = pcr.Robot.default()
    q = pcr.sample_configurations(default, count=12, seed=1)["calibration"]
    measured = pcr.VirtualRobot(default, seed=1).measure(q)["measured"]
    _, result = pcr.calibrate(default, q, measured,
                              stages=[{"name": "ext", "free": ["extrinsics"]}])
    assert np.array_equal([p.nominal for p in result.parameters][:39], default.parameters)
