"""pcr.Robot: the description, attribute access, copies, load/save, errors."""
import json
import math
import os
import pickle

import numpy as np
import pytest

import pcr


def test_package_is_the_expected_one():
    # PCR_EXPECT_INSTALLED=1 (ctest with PCR_PYTEST_INSTALLED, as `scripts/run.sh test` runs it):
    # the package `pip install ./python` put into site-packages, not the build tree's copy.
    where = os.path.realpath(pcr.__file__)
    if os.environ.get("PCR_EXPECT_INSTALLED") == "1":
        assert "site-packages" in where.split(os.sep), where
    assert os.path.isfile(pcr._pcr.__file__)


def test_default_robot_matches_readme(robot):
    # docs/kinematics.md, "The default robot": A_i on a circle of 60 mm cos 20 deg, l = 30 mm,
    # d = 125 um.
    assert robot.name == "femto-3pf"
    assert robot.num_limbs == 3
    for i, limb in enumerate(robot.limbs):
        phi = math.radians(-90 + 120 * i)
        r = 0.060 * math.cos(math.radians(20))
        assert limb.A == pytest.approx([r * math.cos(phi), r * math.sin(phi)], abs=1e-15)
        assert limb.alpha == pytest.approx(phi + math.radians(160))
        assert limb.l == 0.03 and limb.d == 125e-6 and limb.E == 69e9
        assert limb.q_range == (-0.0105, 0.0105)
        assert limb.EI == pytest.approx(69e9 * math.pi * 125e-6 ** 4 / 64)
    assert robot.uncertainty.global_.l == pytest.approx(126e-6)
    assert list(robot.uncertainty.camera) == pytest.approx([1e-3, 1e-3, 0.05])


def test_attribute_edits_are_in_place(robot):
    robot.limbs[1].l = 0.031
    robot.limbs[2].A[0] = 0.001
    robot.extrinsics.camera.x = 0.002
    robot.uncertainty.limbs[0].l = 1e-5
    assert robot.limbs[1].l == 0.031
    assert robot.limbs[2].A[0] == 0.001
    assert robot.extrinsics.camera.x == 0.002
    data = json.loads(robot.to_json())
    assert data["limbs"][1]["l"] == 0.031
    assert data["limbs"][2]["A"][0] == 0.001
    assert data["extrinsics"]["camera"][0] == 0.002
    assert data["uncertainty"]["limbs"][0]["l"] == 1e-5


def test_copy_with_changes_leaves_original(robot):
    other = robot.replace(name="other", E=70e9)
    assert other.name == "other" and other.E == 70e9
    assert all(l.E == 70e9 for l in other.limbs)
    assert robot.name == "femto-3pf" and robot.E == 69e9 and robot.limbs[0].E == 69e9
    third = robot.with_limb(1, l=0.0301)
    assert third.limbs[1].l == 0.0301 and robot.limbs[1].l == 0.03
    assert pcr.Pose(1, 2, 3).replace(theta=0.5) == pcr.Pose(1, 2, 0.5)
    with pytest.raises(AttributeError):
        robot.replace(lenght=1)
    again = pickle.loads(pickle.dumps(robot))
    assert again.to_json() == robot.to_json()


def test_save_load_round_trip(robot, tmp_path):
    robot.limbs[0].gamma = 1.234567890123e-3
    robot.limbs[2].E = 70.5e9
    robot.extrinsics.pattern = pcr.Pose(1e-3, -2e-3, 0.1)
    path = str(tmp_path / "robot.json")
    robot.save(path)
    loaded = pcr.Robot.load(path)
    assert loaded.to_json() == robot.to_json()
    assert loaded.limbs[0].gamma == 1.234567890123e-3  # bit-exact
    assert loaded.limbs[2].E == 70.5e9 and loaded.limbs[1].E == 69e9
    assert loaded.extrinsics.pattern == pcr.Pose(1e-3, -2e-3, 0.1)
    assert os.listdir(tmp_path) == ["robot.json"]  # no temporary left behind


def test_load_errors_are_value_errors_or_file_not_found(tmp_path):
    bad = json.loads(pcr.Robot.default().to_json())
    bad["limbs"][2]["l"] = -0.03
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(bad))
    with pytest.raises(ValueError, match=r"bad\.json: limbs\[2\]\.l: outside its physical range .*, got -0\.03"):
        pcr.Robot.load(str(path))
    with pytest.raises(FileNotFoundError, match="missing.json"):  # as open() raises
        pcr.Robot.load(str(tmp_path / "missing.json"))
    with pytest.raises(ValueError, match="syntax"):
        pcr.Robot.from_json("{", "text")


def test_save_refuses_invalid_description(robot, tmp_path):
    robot.limbs[0].d = -1.0
    with pytest.raises(ValueError, match=r"limbs\[0\]\.d"):
        robot.save(str(tmp_path / "x.json"))
    assert not os.listdir(tmp_path)


def test_limbs_assignment_checks_count(robot):
    with pytest.raises(ValueError, match="2 to 6 limbs"):
        robot.limbs = [robot.limbs[0]]
    two = robot.copy()
    two.limbs = robot.limbs[:2]
    assert two.num_limbs == 2


def _pre_stressed_robot(n=4):
    """The default limb design n times, 360/n degrees apart (tests/random_robots.hpp's
    regular_robot), rods 1 and n - 1 300 um and 200 um longer: bowed, pre-stressed, at home."""
    base = pcr.Robot.default()
    design = base.limbs[0]
    r_a = float(np.hypot(*design.A))
    turn = design.alpha - math.atan2(design.A[1], design.A[0])
    limbs = []
    for i in range(n):
        phi = -math.pi / 2 + 2 * math.pi * i / n
        limb = design.replace()
        limb.A = (r_a * math.cos(phi), r_a * math.sin(phi))
        limb.alpha = phi + turn
        limb.B = limb.A + design.l * np.array([math.cos(limb.alpha), math.sin(limb.alpha)])
        limb.beta = limb.alpha
        limbs.append(limb)
    limbs[1].l += 300e-6
    limbs[n - 1].l += 200e-6
    robot = base.copy()
    robot.uncertainty = None
    robot.limbs = limbs
    return robot


def test_home_bow_says_which_home_a_pre_stressed_robot_is_in(tmp_path):
    robot = _pre_stressed_robot()
    assert all(limb.home_bow is None for limb in robot.limbs)
    unsaid = robot.home().pose.to_array()
    left = robot.copy()
    left.limbs = [limb.replace(home_bow="left") for limb in robot.limbs]
    home = left.home().pose.to_array()
    assert np.hypot(*(home[:2] - unsaid[:2])) > 1e-6  # another home
    for pose in (unsaid, home):
        homed = robot.with_home_at(pcr.Pose(*pose))
        assert homed.home().pose.to_array() == pytest.approx(pose, abs=1e-12)
    # Kept by the file, copies and pickles; anything but 'left', 'right' or None is refused.
    left.save(tmp_path / "left.json")
    assert [limb.home_bow for limb in pcr.Robot.load(tmp_path / "left.json").limbs] == ["left"] * 4
    assert [limb.home_bow for limb in pickle.loads(pickle.dumps(left)).limbs] == ["left"] * 4
    with pytest.raises(ValueError, match="home_bow.*'up'"):
        left.limbs[0].home_bow = "up"


def _matrix(pose):
    x, y, theta = pose
    c, s = np.cos(theta), np.sin(theta)
    return np.array([[c, -s, x], [s, c, y], [0.0, 0.0, 1.0]])


def test_compose_poses_is_the_product_of_homogeneous_matrices():
    rng = np.random.default_rng(5)
    a = rng.uniform(-1, 1, size=(7, 3)) * [0.1, 0.1, np.pi]
    b = rng.uniform(-1, 1, size=(7, 3)) * [0.1, 0.1, np.pi]
    for rows, single in ((pcr.compose_poses(a, b), None), (pcr.compose_poses(a[2], b), 2),
                         (pcr.compose_poses(a, b[4]), 4)):
        assert rows.shape == (7, 3)
        for k in range(7):
            ak = a[single] if single == 2 else a[k]
            bk = b[single] if single == 4 else b[k]
            m = _matrix(ak) @ _matrix(bk)
            assert rows[k, :2] == pytest.approx(m[:2, 2], abs=1e-15)
            assert np.cos(rows[k, 2]) == pytest.approx(m[0, 0], abs=1e-15)
            assert np.sin(rows[k, 2]) == pytest.approx(m[1, 0], abs=1e-15)
    single = pcr.compose_poses(a[0], b[0])
    assert single.shape == (3,)
    assert single.tolist() == (pcr.Pose(*a[0]) * pcr.Pose(*b[0])).to_array().tolist()
    with pytest.raises(ValueError, match="3 and 2 rows do not broadcast"):
        pcr.compose_poses(a[:3], b[:2])
    with pytest.raises(ValueError, match="a: "):
        pcr.compose_poses([0.0, np.nan, 0.0], b[0])
