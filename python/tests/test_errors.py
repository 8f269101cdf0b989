"""What a Python user expects of the bindings' arguments: paths as str or any os.PathLike,
FileNotFoundError for a missing input (as open() raises), and ValueError naming the argument,
what it expects and what it got for a bad vector or number, with no command-line flag in it."""
import errno
import json
import math
import os
import pathlib
import re
import subprocess

import numpy as np
import pytest

import pcr

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
NAN = float("nan")

needs_calibration = pytest.mark.skipif(not pcr.has_calibration, reason="pcr::calib not built")
needs_vision = pytest.mark.skipif(not getattr(pcr, "has_vision", False),
                                  reason="pcr::vision not built")


class Where(os.PathLike):
    """An os.PathLike that is not a pathlib.Path."""

    def __init__(self, path):
        self.path = str(path)

    def __fspath__(self):
        return self.path


def raises(exception, message, function, *args, **kwargs):
    """Calls function, checks it raises `exception` whose text is exactly `message` (a str) or
    matches it (a compiled pattern), and that the text names no command-line option."""
    with pytest.raises(exception) as info:
        function(*args, **kwargs)
    text = str(info.value)
    if isinstance(message, str):
        assert text == message
    else:
        assert message.search(text), text
    assert not re.search(r"(^|\s|\()--\w", text), f"a command-line flag in: {text}"
    return info.value


# ---- paths -------------------------------------------------------------------------------------
def test_robot_load_save_take_any_path(robot, tmp_path):
    robot.limbs[1].l = 0.0301
    for path in (tmp_path / "a.json", Where(tmp_path / "b.json"), str(tmp_path / "c.json")):
        robot.save(path)
        assert pcr.Robot.load(path).to_json() == robot.to_json()
    assert sorted(os.listdir(tmp_path)) == ["a.json", "b.json", "c.json"]


def test_missing_robot_is_file_not_found(tmp_path):
    missing = tmp_path / "missing.json"
    for path in (missing, str(missing), Where(missing)):
        error = raises(FileNotFoundError, f"[Errno 2] No such file or directory: '{missing}'",
                       pcr.Robot.load, path)
        assert error.errno == errno.ENOENT and error.filename == str(missing)
    # A file that is there but is no robot stays a ValueError naming it.
    raises(ValueError, re.compile(r"^" + re.escape(str(tmp_path)) + ": is a directory"),
           pcr.Robot.load, tmp_path)


def test_paths_must_be_paths(robot):
    with pytest.raises(TypeError, match="PathLike"):
        pcr.Robot.load(3)
    with pytest.raises(TypeError, match="PathLike"):
        robot.save(None)


@needs_calibration
def test_calibration_files_take_any_path(robot, tmp_path):
    q = np.array([[0.001, 0.002, 0.003], [-1e-3, 1e-3 / 3, 0.0]])
    measured = np.array([[1e-4, 2e-4, 0.01], [math.pi * 1e-5, -1e-6, -0.02]])
    pcr.write_dataset(tmp_path / "data.csv", q, measured)
    q2, m2 = pcr.read_dataset(Where(tmp_path / "data.csv"))
    assert np.array_equal(q2, q) and np.array_equal(m2, measured)
    pcr.write_configurations(Where(tmp_path / "q.csv"), q)
    assert np.array_equal(pcr.read_configurations(tmp_path / "q.csv"), q)

    (tmp_path / "stages.json").write_text(json.dumps({"stages": pcr.default_stages()}))
    assert pcr.load_calibration_stages(tmp_path / "stages.json") == pcr.default_stages()

    poses = pcr.circle_path(count=5)
    (tmp_path / "path.csv").write_text(
        "x,y,theta\n" + "".join(f"{x!r},{y!r},{t!r}\n" for x, y, t in poses.tolist()))
    np.testing.assert_array_equal(pcr.load_path_csv(tmp_path / "path.csv"), poses)

    attained = np.stack([poses + [1e-6, 0, 0], poses - [0, 1e-6, 0]], axis=1)  # (5, 2, 3)
    (tmp_path / "measured.csv").write_text(pcr.measured_to_csv(poses, attained))
    commanded, back = pcr.load_measured_csv(Where(tmp_path / "measured.csv"))
    np.testing.assert_allclose(commanded, poses, rtol=0, atol=1e-15)
    np.testing.assert_allclose(back, attained, rtol=0, atol=1e-15)


@needs_calibration
@pytest.mark.parametrize("read", ["read_dataset", "read_configurations",
                                  "load_calibration_stages", "load_path_csv", "load_measured_csv"])
def test_missing_calibration_inputs_are_file_not_found(read, tmp_path):
    missing = tmp_path / "missing.csv"
    error = raises(FileNotFoundError, f"[Errno 2] No such file or directory: '{missing}'",
                   getattr(pcr, read), missing)
    assert error.filename == str(missing)


@needs_calibration
def test_missing_stages_file_of_calibrate(robot, tmp_path):
    q = pcr.sensitivity_configurations(robot, 2e-3)[:4]
    measured = np.zeros((4, 3))
    for stages in (tmp_path / "stages.json", Where(tmp_path / "stages.json")):
        raises(FileNotFoundError, re.compile(r"stages\.json'$"), pcr.calibrate, robot, q,
               measured, stages=stages)


@needs_vision
def test_vision_files_take_any_path(tmp_path):
    image = np.linspace(0, 1, 12 * 20, dtype=np.float32).reshape(12, 20)
    pcr.write_png(tmp_path / "a.png", image, bits=16)
    assert np.max(np.abs(pcr.read_image(Where(tmp_path / "a.png")) - image)) < 1e-4
    cam = pcr.Camera(800, 600, [[900.0, 0, 400], [0, 900.0, 300], [0, 0, 1]])
    cam.save(tmp_path / "camera.yaml")
    np.testing.assert_allclose(pcr.load_camera(Where(tmp_path / "camera.yaml")).K, cam.K)
    layout = pcr.load_mounts(pathlib.Path(ROOT) / "data" / "mounts-femto-3pf.json")
    assert len(layout) == len(pcr.default_mounts())


@needs_vision
def test_missing_vision_inputs_are_file_not_found(tmp_path):
    missing = tmp_path / "missing.png"
    text = f"[Errno 2] No such file or directory: '{missing}'"
    raises(FileNotFoundError, text, pcr.read_image, missing)
    raises(FileNotFoundError, text, pcr.load_camera, missing)
    raises(FileNotFoundError, text, pcr.load_mounts, missing)
    raises(FileNotFoundError, text, pcr.calibrate_camera, [missing, Where(missing)])


# ---- vectors and numbers -----------------------------------------------------------------------
def test_force_and_moment_are_checked(robot):
    q = [0.001, 0.0, -0.001]
    raises(ValueError, "force: expected 2 finite numbers (fx, fy in N), got 3 numbers (1, 0, 0)",
           robot.forward, q, force=(1, 0, 0))
    raises(ValueError, "force: expected 2 finite numbers (fx, fy in N), got (nan, 0)",
           robot.forward, q, force=(NAN, 0))
    raises(ValueError, "force: expected 2 finite numbers (fx, fy in N), got (0, inf)",
           robot.inverse, [0, 0, 0], force=np.array([0, np.inf]))
    raises(ValueError, "force: expected 2 finite numbers (fx, fy in N), got 'ab'",
           robot.home, force="ab")
    raises(ValueError, "force: expected 2 finite numbers (fx, fy in N), got None",
           robot.home, force=None)
    raises(ValueError, "moment: expected a number from -1000 to 1000 (N m), got nan",
           robot.forward, q, moment=NAN)
    # defaults, tuples, lists and arrays all work
    assert robot.forward(q).converged and robot.home().converged
    loaded = [robot.forward(q, force=f, moment=1e-5).pose.x
              for f in ((1e-3, 0), [1e-3, 0.0], np.array([1e-3, 0]))]
    assert loaded[0] == loaded[1] == loaded[2] != robot.forward(q).pose.x


def test_vector_attributes_are_checked(robot):
    limb = robot.limbs[0]
    raises(ValueError, "Limb.A: expected 2 finite numbers (x, y in m), got 3 numbers (1, 2, 3)",
           setattr, limb, "A", (1, 2, 3))
    raises(ValueError, "Limb.B: expected 2 finite numbers (x, y in m), got (nan, 0.001)",
           setattr, limb, "B", [NAN, 1e-3])
    raises(ValueError, re.compile(r"^Uncertainty\.camera: expected 3 finite numbers .*, got 2 "
                                  r"numbers \(0\.001, 0\.001\)$"),
           setattr, robot.uncertainty, "camera", (1e-3, 1e-3))
    raises(ValueError, re.compile(r"^LimbUncertainty\.A: expected 2 finite numbers"),
           setattr, robot.uncertainty.limbs[0], "A", 1e-6)
    limb.A = (0.01, -0.02)
    robot.uncertainty.pattern = np.array([1e-4, 2e-4, 1e-3])
    assert list(robot.limbs[0].A) == [0.01, -0.02]
    assert list(robot.uncertainty.pattern) == [1e-4, 2e-4, 1e-3]


@needs_calibration
def test_sensitivity_arguments_are_checked_up_front(robot):
    raises(ValueError, "centre: expected 3 finite numbers (joint values in m), got (nan, 0, 0)",
           pcr.sensitivity, robot, centre=[NAN, 0, 0])
    raises(ValueError, "centre: expected 3 finite numbers (joint values in m), got 2 numbers "
           "(0, 0)", pcr.sensitivity, robot, centre=[0, 0])
    raises(ValueError, "sensitivity: centre: joint q2 at 0.02 m is outside its stroke q_range "
           "[-0.0105, 0.0105] m", pcr.sensitivity, robot, centre=[0, 0.02, 0])
    raises(ValueError, "step: expected a number from 1e-06 to 0.01 (m), got nan",
           pcr.sensitivity, robot, step=NAN)
    raises(ValueError, "step: expected a number from 1e-06 to 0.01 (m), got 1e-300",
           pcr.sensitivity, robot, step=1e-300)
    raises(ValueError, "step: expected a number from 1e-06 to 0.01 (m), got 0",
           pcr.sensitivity_configurations, robot, 0.0)
    raises(ValueError, "moment: expected a number from -1000 to 1000 (N m), got inf",
           pcr.sensitivity, robot, moment=math.inf)
    raises(ValueError, "force: expected 2 finite numbers (fx, fy in N), got 1 number (0)",
           pcr.sensitivity, robot, force=[0])
    # The library's own message when FK fails speaks of no particular interface.
    raises(RuntimeError, re.compile(r"no forward-kinematics solution at q = .*a smaller step"),
           pcr.sensitivity, robot, centre=[0.0105, 0.0105, -0.0105], step=0.01)


@needs_calibration
def test_calibration_numbers_are_checked(robot):
    path = pcr.square_path(count=4)
    raises(ValueError, "centre: expected 2 finite numbers (x, y in m), got 3 numbers (0, 0, 0)",
           pcr.square_path, centre=(0, 0, 0))
    raises(ValueError, "centre: expected 2 finite numbers (x, y in m), got (0, nan)",
           pcr.circle_path, centre=(0, NAN))
    raises(ValueError, "side: expected a number from 1e-06 to 0.1 (m), got nan",
           pcr.square_path, NAN)
    raises(ValueError, "start_angle: expected a finite number (rad), got nan",
           pcr.circle_path, start_angle=NAN)
    raises(ValueError, "strain_limit: expected a number from 1e-06 to 0.1, got nan",
           pcr.command_path, robot, path, strain_limit=NAN)
    raises(ValueError, "force: expected 2 finite numbers (fx, fy in N), got 3 numbers (0, 0, 0)",
           pcr.command_path, robot, path, force=(0, 0, 0))
    raises(ValueError, "min_distance: expected a number from 0 to 0.1 (m), got nan",
           pcr.poisson_disc_sample, robot, count=3, min_distance=NAN)
    raises(ValueError, "force: expected 2 finite numbers (fx, fy in N), got 3 numbers (0, 0, 0)",
           pcr.VirtualRobot, robot, force=(0, 0, 0))
    raises(ValueError, "force: expected 2 finite numbers (fx, fy in N), got (nan, 0)",
           pcr.platform_parameter_jacobian, robot, [0, 0, 0], force=(NAN, 0))
    # a moment without a force is applied, not dropped
    assert pcr.VirtualRobot(robot, moment=1e-4).load[1] == 1e-4


@needs_calibration
def test_paths_take_the_library_ranges():
    raises(ValueError, "theta: expected a number from -3.141592653589793 to 3.141592653589793 "
           "(rad), got 4", pcr.square_path, theta=4.0)
    raises(ValueError, "diameter: expected a number from 1e-06 to 0.1 (m), got 0.2",
           pcr.circle_path, 0.2)
    raises(ValueError, "centre: expected a number from -0.1 to 0.1 (m), got -0.5",
           pcr.circle_path, centre=(0.0, -0.5))
    raises(ValueError, "num_poses: expected a number from 1 to 100000, got 100001",
           pcr.square_path, count=100001)


@needs_vision
def test_vision_vectors_and_numbers_are_checked(robot):
    layout = pcr.default_mounts()
    raises(ValueError, "platform: expected a pcr.Pose or 3 finite numbers (x m, y m, theta rad), "
           "got 2 numbers (0, 0)", pcr.mount_tags, robot, layout, platform=(0, 0))
    raises(ValueError, "platform: expected a pcr.Pose or 3 finite numbers (x m, y m, theta rad), "
           "got (nan, 0, 0)", pcr.render_robot, robot, layout, platform=pcr.Pose(NAN, 0, 0))
    raises(ValueError, "board_pose: expected a pcr.Pose or 3 finite numbers (x m, y m, theta "
           "rad), got 4 numbers (0, 0, 0, 0)", pcr.render_chessboard, board_pose=[0, 0, 0, 0])
    raises(ValueError, "tilt_x: expected a number from -1 to 1 (rad), got nan",
           pcr.render_robot, robot, layout, tilt_x=NAN)
    raises(ValueError, "blur: expected a number from 0 to 50 (px), got nan",
           pcr.render_chessboard, blur=NAN)
    cam = pcr.Camera(800, 600, np.eye(3))
    raises(ValueError, "point_camera: expected 3 finite numbers (x, y, z in m), got 2 numbers "
           "(1, 2)", cam.project, (1, 2))
    assert len(pcr.mount_tags(robot, layout, platform=pcr.Pose(0, 0, 0))) == len(layout)


@pytest.mark.parametrize("command, option, value, call, message", [
    (["sample", "--output", "s.csv"], "--strain-limit", 0.5,
     lambda robot: pcr.poisson_disc_sample(robot, count=3, strain_limit=0.5),
     "strain_limit: expected a number from 1e-06 to 0.1, got 0.5"),
    (["sample", "--output", "s.csv"], "--min-distance", 0.2,
     lambda robot: pcr.poisson_disc_sample(robot, count=3, min_distance=0.2),
     "min_distance: expected a number from 0 to 0.1 (m), got 0.2"),
    (["simulate", "--input", "q.csv", "--output", "d.csv"], "--noise-angle", 0.2,
     lambda robot: pcr.VirtualRobot(robot, noise_angle=0.2),
     "noise_angle: expected a number from 0 to 0.1 (rad), got 0.2"),
    (["sensitivity"], "--step", 0.02, lambda robot: pcr.sensitivity(robot, step=0.02),
     "step: expected a number from 1e-06 to 0.01 (m), got 0.02"),
    (["accuracy"], "--strain-limit", 0.0,
     lambda robot: pcr.command_path(robot, pcr.square_path(), strain_limit=0.0),
     "strain_limit: expected a number from 1e-06 to 0.1, got 0"),
    (["accuracy"], "--size", 0.5, lambda robot: pcr.square_path(0.5),
     "side: expected a number from 1e-06 to 0.1 (m), got 0.5"),
    (["accuracy"], "--centre", 0.2, lambda robot: pcr.square_path(centre=(0.2, 0.0)),
     "centre: expected a number from -0.1 to 0.1 (m), got 0.2"),
    (["accuracy"], "--theta", 4.0, lambda robot: pcr.square_path(theta=4.0),
     "theta: expected a number from -3.141592653589793 to 3.141592653589793 (rad), got 4"),
    (["accuracy"], "--count", 0, lambda robot: pcr.circle_path(count=0),
     "num_poses: expected a number from 1 to 100000, got 0"),
    (["demo", "--no-vision"], "--poses", 0,
     lambda robot: pcr.run_method(robot, pcr.VirtualRobot(robot), square_poses=0),
     "square.num_poses: expected a number from 1 to 100000, got 0"),
    (["fk"], "--moment", 2000.0, lambda robot: robot.forward([0.0, 0.0, 0.0], moment=2000.0),
     "moment: expected a number from -1000 to 1000 (N m), got 2000"),
    (["sample", "--output", "s.csv"], "--box", 2.0,
     lambda robot: pcr.poisson_disc_sample(robot, count=3, box_min=[2.0] * 3, box_max=[2.0] * 3),
     "box_min: expected a number from -1 to 1 (m), got 2"),
])
def test_the_cli_and_python_refuse_what_the_library_refuses(cli, robot, tmp_path, command,
                                                            option, value, call, message):
    """The range of an option lives in the library: Python reports its message, the CLI names
    its option with the same range."""
    raises(ValueError, message, call, robot)
    out = subprocess.run([cli, *command, option, repr(value)], capture_output=True, text=True,
                         cwd=tmp_path, check=False, timeout=60)
    assert out.returncode != 0
    bounds = message.split("expected a number from ")[1].split(", got")[0]
    lo, hi = bounds.split(" (")[0].split(" to ")
    assert f"{option}: '{value!r}' is outside [{lo}, {hi}]" in out.stderr, out.stderr
    assert os.listdir(tmp_path) == []
