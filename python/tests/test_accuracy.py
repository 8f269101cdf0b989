"""Trajectories and ISO 9283 accuracy, against geometry, hand-computed statistics and FK."""
import numpy as np
import pytest

import pcr
import pcr.plot

pytestmark = pytest.mark.skipif(not pcr.has_calibration, reason="pcr::calib not built")


def wrap(a):
    return np.arctan2(np.sin(a), np.cos(a))


def test_square_side_corners_and_closure():
    side, centre, rot = 2e-3, (1e-4, -2e-4), 0.3
    p = pcr.square_path(side, centre=centre, rotation=rot, theta=0.01, count=40)
    assert p.shape == (40, 3)
    assert np.all(p[:, 2] == 0.01)
    # closed, evenly spaced: 40 steps of perimeter / 40, the last one back to the start
    steps = np.hypot(*np.diff(np.vstack([p, p[:1]])[:, :2], axis=0).T)
    np.testing.assert_allclose(steps, 4 * side / 40, rtol=1e-12)
    # corners every 10 poses, counter-clockwise from (-s/2, -s/2) rotated by rot about the centre
    c, s = np.cos(rot), np.sin(rot)
    local = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]]) * side / 2
    expected = np.column_stack([c * local[:, 0] - s * local[:, 1],
                                s * local[:, 0] + c * local[:, 1]]) + centre
    np.testing.assert_allclose(p[::10, :2], expected, atol=1e-15)


def test_circle_radius_and_spacing():
    p = pcr.circle_path(3e-3, centre=(5e-4, 0.0), start_angle=0.5, count=36)
    assert p.shape == (36, 3)
    r = np.hypot(p[:, 0] - 5e-4, p[:, 1])
    np.testing.assert_allclose(r, 1.5e-3, rtol=1e-12)
    phi = np.unwrap(np.arctan2(p[:, 1], p[:, 0] - 5e-4))
    np.testing.assert_allclose(phi, 0.5 + 2 * np.pi * np.arange(36) / 36, atol=1e-12)
    with pytest.raises(ValueError, match="num_poses"):
        pcr.circle_path(count=0)


def test_load_path_csv(tmp_path):
    poses = pcr.circle_path(count=5)
    f = tmp_path / "path.csv"
    f.write_text("# a path\nx,y,theta\n" + "".join(f"{x!r},{y!r},{t!r}\n" for x, y, t in poses.tolist()))
    np.testing.assert_array_equal(pcr.load_path_csv(str(f)), poses)
    bad = tmp_path / "bad.csv"
    bad.write_text("x,y,theta\n0,0,0\n0,zero,0\n")
    with pytest.raises(ValueError, match="bad.csv"):
        pcr.load_path_csv(str(bad))


def test_command_path_reaches_the_poses(robot):
    path = pcr.square_path(count=8)
    c = pcr.command_path(robot, path)
    assert c["q"].shape == (8, 3) and c["max_strain"].shape == (8,)
    fk = robot.forward(c["q"])  # independent check: FK of the commanded joints
    assert fk.converged.all()
    # IK and FK each within the default accuracy of the exact model (1 nm, 1 urad).
    np.testing.assert_allclose(fk.pose[:, :2], path[:, :2], atol=1e-9)
    np.testing.assert_allclose(fk.pose[:, 2], path[:, 2], atol=1e-6)
    far = np.vstack([path[:2], [[0.5, 0.0, 0.0]]])  # 0.5 m away: out of reach
    with pytest.raises(ValueError, match="pose 2"):
        pcr.command_path(robot, far)
    with pytest.raises(ValueError, match=r"\(N, 3\)"):
        pcr.command_path(robot, np.zeros((4, 2)))


def iso_reference(commanded, attained):
    """ISO 9283 Eqs. 10, 11 and RP, written out independently."""
    out = []
    for c, a in zip(commanded, attained):
        a = np.asarray(a)
        xb, yb = a[:, 0].mean(), a[:, 1].mean()
        tb = c[2] + wrap(a[:, 2] - c[2]).mean()
        lj = np.hypot(a[:, 0] - xb, a[:, 1] - yb)
        n = len(a)
        s_l = np.sqrt(np.sum((lj - lj.mean()) ** 2) / (n - 1))
        s_t = np.sqrt(np.sum((a[:, 2] - tb) ** 2) / (n - 1))
        out.append(dict(ap_p=np.hypot(xb - c[0], yb - c[1]), ap_theta=tb - c[2],
                        rp_l=lj.mean() + 3 * s_l, rp_theta=3 * s_t, barycentre=(xb, yb, tb)))
    return out


def test_iso9283_hand_made_example():
    # pose 0: four attained poses at +-a about (b, 0): AP_p = b, l_j = a, S_l = 0, RP_l = a;
    # theta = u +- t: AP_theta = u, S_theta = t sqrt(4 / 3).
    a, b, u, t = 2e-6, 5e-6, 3e-6, 1e-6
    commanded = np.array([[0.0, 0.0, 0.0], [1e-3, 1e-3, 0.1]])
    att0 = np.array([[b + a, 0, u + t], [b - a, 0, u - t], [b, a, u + t], [b, -a, u - t]])
    att1 = commanded[1] + np.array([[1e-6, 2e-6, -1e-6], [-3e-6, 0.5e-6, 2e-6],
                                    [0.0, -1e-6, 0.0], [2e-6, 1e-6, 4e-6]])
    r = pcr.iso9283(commanded, np.stack([att0, att1]))
    assert isinstance(r, pcr.Iso9283Result) and len(r) == 2
    np.testing.assert_allclose(r.ap_p[0], b, rtol=1e-9)
    np.testing.assert_allclose(r.ap_theta[0], u, rtol=1e-9)
    np.testing.assert_allclose(r.l_bar[0], a, rtol=1e-9)
    assert abs(r.s_l[0]) < 1e-15
    np.testing.assert_allclose(r.rp_l[0], a, rtol=1e-9)
    np.testing.assert_allclose(r.s_theta[0], t * np.sqrt(4 / 3), rtol=1e-9)
    ref = iso_reference(commanded, [att0, att1])
    for k in range(2):
        np.testing.assert_allclose(r.ap_p[k], ref[k]["ap_p"], rtol=1e-9)
        np.testing.assert_allclose(r.ap_theta[k], ref[k]["ap_theta"], rtol=1e-9, atol=1e-15)
        np.testing.assert_allclose(r.rp_l[k], ref[k]["rp_l"], rtol=1e-9)
        np.testing.assert_allclose(r.rp_theta[k], ref[k]["rp_theta"], rtol=1e-9)
        np.testing.assert_allclose(r.barycentre[k], ref[k]["barycentre"], rtol=1e-12, atol=1e-15)
    np.testing.assert_array_equal(r.cycles, [4, 4])
    s = r.summary
    aps = [ref[0]["ap_p"], ref[1]["ap_p"]]
    np.testing.assert_allclose([s["ap_p"]["max"], s["ap_p"]["mean"], s["ap_p"]["min"]],
                               [max(aps), np.mean(aps), min(aps)], rtol=1e-9)
    # ragged input (a list of (R_k, 3)) gives the same for the common poses
    r2 = pcr.iso9283(commanded, [att0, att1[:3]])
    np.testing.assert_array_equal(r2.cycles, [4, 3])
    assert r2.ap_p[0] == r.ap_p[0]
    assert "AP" in pcr.iso9283_table({"example": r}) and '"example"' in pcr.iso9283_json([("example", r)])
    assert r.poses_csv().splitlines()[0].startswith("pose,x_c,y_c,theta_c")
    with pytest.raises(ValueError, match="commanded"):
        pcr.iso9283(commanded[:1], [att0, att1])
    with pytest.raises(ValueError, match="pose 1"):
        pcr.iso9283(commanded, [att0, att1[:1]])
    with pytest.raises(ValueError):
        pcr.iso9283(commanded, [att0, np.full((3, 3), np.nan)])


def test_evaluate_on_virtual_robot_matches_fk_of_the_truth(robot, tmp_path):
    v = pcr.VirtualRobot(robot, seed=2, noise_position=0.0, noise_angle=0.0)
    path = pcr.square_path(count=8)
    ev = pcr.evaluate_on_virtual_robot(robot, v, path, repeat=2, frame="true")
    assert ev.attained.shape == (8, 2, 3) and ev.q.shape == (8, 3) and len(ev) == 8
    np.testing.assert_array_equal(ev.commanded, path)
    # Reference: the truth's FK at the commanded joints (no noise, true extrinsics = W exactly).
    fk = v.truth.forward(ev.q)
    assert fk.converged.all()
    for cycle in range(2):
        # Solved along other warm-start histories: each within 1 nm / 1 urad of the exact model.
        np.testing.assert_allclose(ev.attained[:, cycle, :2], fk.pose[:, :2], atol=1e-9)
        np.testing.assert_allclose(ev.attained[:, cycle, 2], fk.pose[:, 2], atol=1e-6)
    np.testing.assert_allclose(ev.iso.ap_p, np.hypot(*(fk.pose[:, :2] - path[:, :2]).T),
                               rtol=1e-6, atol=1e-9)
    assert ev.iso.summary["ap_p"]["mean"] > 1e-6  # the nominal model is visibly off the truth
    # Commanded with the truth itself, the robot reaches the path (frame model = its own).
    v2 = pcr.VirtualRobot(robot, seed=2, noise_position=0.0, noise_angle=0.0)
    exact = pcr.evaluate_on_virtual_robot(v2.truth, v2, path, repeat=2)
    assert exact.iso.summary["ap_p"]["max"] < 1e-9
    assert exact.iso.summary["ap_theta_abs"]["max"] < 1e-6
    pcr.plot.plot_trajectory_accuracy(ev, path=tmp_path / "ev.png")
    pcr.plot.plot_trajectory_accuracy(ev.iso, path=tmp_path / "iso.png")
    assert (tmp_path / "ev.png").stat().st_size > 2000
    with pytest.raises(ValueError, match="frame"):
        pcr.evaluate_on_virtual_robot(robot, v, path, frame="camera")
    with pytest.raises(ValueError, match="repeat"):
        pcr.evaluate_on_virtual_robot(robot, v, path, repeat=1)


def test_repeatability_follows_the_camera_noise(robot):
    sigma = 9.13e-9
    v = pcr.VirtualRobot(robot, seed=3, noise_position=sigma, noise_angle=1.2e-6)
    ev = pcr.evaluate_on_virtual_robot(v.truth, v, pcr.circle_path(count=12), repeat=30)
    # 2-D Gaussian scatter: E|l| = sigma sqrt(pi / 2), std(l) = sigma sqrt(2 - pi / 2)
    mean_rp = ev.iso.summary["rp_l"]["mean"]
    expected = sigma * (np.sqrt(np.pi / 2) + 3 * np.sqrt(2 - np.pi / 2))
    assert 0.8 * expected < mean_rp < 1.2 * expected
    np.testing.assert_allclose(ev.iso.s_theta.mean(), 1.2e-6, rtol=0.2)


def test_measured_csv_round_trip(tmp_path):
    rng = np.random.default_rng(4)
    commanded = pcr.circle_path(count=4)
    attained = commanded[:, None, :] + 1e-7 * rng.standard_normal((4, 3, 3))
    f = tmp_path / "measured.csv"
    f.write_text(pcr.measured_to_csv(commanded, attained))
    c2, a2 = pcr.load_measured_csv(str(f))
    np.testing.assert_array_equal(c2, commanded)
    np.testing.assert_allclose(a2, attained, rtol=1e-15, atol=0)
    bad = tmp_path / "broken.csv"
    bad.write_text("pose,x_c,y_c,theta_c,x,y,theta\n0,0,0,0,0,0,0\n2,0,0,0,0,0,0\n")
    with pytest.raises(ValueError, match="broken.csv"):
        pcr.load_measured_csv(str(bad))
