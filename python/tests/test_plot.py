"""Each plot renders to a non-empty PNG with the Agg backend."""
import matplotlib

matplotlib.use("Agg")

import matplotlib.image  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

import pcr  # noqa: E402
import pcr.plot  # noqa: E402


def check_png(path):
    data = open(path, "rb").read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 2000
    image = matplotlib.image.imread(path)
    assert image.ndim == 3 and image.shape[0] > 100 and image.shape[1] > 100
    assert np.ptp(image[..., :3]) > 0  # not a blank canvas
    plt.close("all")


def test_plot_robot(robot, tmp_path):
    pcr.plot.plot_robot(robot, [0.004, -0.003, 0.002], path=tmp_path / "one.png")
    check_png(tmp_path / "one.png")
    q = np.linspace([0, 0, 0], [0.006, -0.004, 0.002], 4)
    pcr.plot.plot_robot(robot, q, path=tmp_path / "seq.png")
    check_png(tmp_path / "seq.png")


@pytest.mark.skipif(not pcr.has_calibration, reason="pcr::calib not built")
def test_workspace_maps(robot, tmp_path):
    m = pcr.workspace_map(robot, grid=12)
    assert m["reachable"].shape == (12, 12) and m["q"].shape == (12, 12, 3)
    assert m["reachable_area"] > 0 and m["stable_area"] <= m["reachable_area"]
    cell = (m["x"][1] - m["x"][0]) * (m["y"][1] - m["y"][0])
    assert m["reachable_area"] == pytest.approx(m["reachable"].sum() * cell)
    assert np.all(np.isfinite(m["stability_margin"][m["reachable"]]))
    pcr.plot.plot_workspace_maps(robot, result=m, path=tmp_path / "maps.png")
    check_png(tmp_path / "maps.png")
    reachable, lo, hi = pcr.rotation_range(robot, 0.0, 0.0)
    assert reachable and lo < 0 < hi
    with pytest.raises(ValueError, match="grid"):
        pcr.workspace_map(robot, grid=1)


@pytest.mark.skipif(not pcr.has_calibration, reason="pcr::calib not built")
def test_plot_workspace(robot, tmp_path):
    ws = pcr.workspace(robot, theta=0.0, resolution=9)
    assert ws["reachable"][4, 4]  # the centre (home) is reachable
    assert ws["q"].shape == (9, 9, 3)
    pcr.plot.plot_workspace(robot, result=ws, path=tmp_path / "ws.png")
    check_png(tmp_path / "ws.png")


@pytest.mark.skipif(not pcr.has_calibration, reason="pcr::calib not built")
def test_plot_calibration_errors(robot, tmp_path):
    v = pcr.VirtualRobot(robot, seed=3)
    q = pcr.sensitivity_configurations(robot, 2e-3)
    measured = v.measure(q)["measured"]
    cal, val = (q[:16], measured[:16]), (q[16:], measured[16:])
    pcr.plot.plot_calibration_errors(robot, v.truth, cal, val, path=tmp_path / "cal.png")
    check_png(tmp_path / "cal.png")


def test_plot_trajectory_accuracy(tmp_path):
    t = np.linspace(0, 2 * np.pi, 50)
    commanded = np.column_stack([1e-3 * np.cos(t), 1e-3 * np.sin(t), np.zeros_like(t)])
    attained = commanded + 1e-7 * np.column_stack([np.sin(3 * t), np.cos(5 * t), np.sin(t)])
    pcr.plot.plot_trajectory_accuracy(commanded, attained, path=tmp_path / "traj.png")
    check_png(tmp_path / "traj.png")
    with pytest.raises(ValueError):
        pcr.plot.plot_trajectory_accuracy(commanded, attained[:3])
