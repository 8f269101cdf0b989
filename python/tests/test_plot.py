"""Each plot renders to a non-empty PNG with the Agg backend."""
import matplotlib

matplotlib.use("Agg")

import json  # noqa: E402
import pathlib  # noqa: E402

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
def test_a_long_stroke_map_leaves_points_beyond_the_border_unvisited(tmp_path):
    import pathlib
    robot = pcr.Robot.load(pathlib.Path(__file__).parents[2] / "robots"
                           / "femto-3pf-long-stroke.json")
    one = pcr.workspace_map(robot, grid=14, threads=1)
    two = pcr.workspace_map(robot, grid=14, threads=2)
    for key in ("visited", "reachable", "stable", "status_code", "q", "max_strain"):
        np.testing.assert_array_equal(one[key], two[key])  # NaNs in the same places
    unvisited = ~one["visited"]
    assert unvisited.sum() > 14 * 14 // 4
    assert np.all(one["status_code"][unvisited] == -1)
    assert not one["reachable"][unvisited].any() and np.isnan(one["q"][unvisited]).all()
    with pytest.raises(ValueError, match="threads"):
        pcr.workspace_map(robot, grid=4, threads=-1)
    pcr.plot.plot_workspace_maps(robot, result=one, path=tmp_path / "maps.png")
    check_png(tmp_path / "maps.png")


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


# ---- figures from files: units, colour bars against the data, titles, the demo's figures -----

def texts(fig):
    """Every string the figure shows: titles, labels, legends, texts, colour bar labels."""
    out = [t.get_text() for t in fig.findobj(matplotlib.text.Text)]
    return "\n".join(out)


MAP_COLUMNS = ("x,y,theta,reachable,stable,status,q1,q2,q3,max_strain,stability_margin,"
               "singularity,position_3sigma,orientation_3sigma,worst_position,worst_orientation")


def small_map(path, nx=14, ny=12):
    """A `pcr map` CSV: reachable inside a disc, an unstable patch, two positions without an
    equilibrium (IK singular), a predicted error spanning decades; rows in a shuffled order."""
    x, y = np.meshgrid(np.linspace(-6e-3, 7e-3, nx), np.linspace(-5e-3, 6e-3, ny))
    r = np.hypot(x, y) / 5e-3
    reachable = r < 1
    stable = ~((x > 2e-3) & (y > 2e-3))
    found = np.ones_like(r, bool)
    found[-1, -2:] = False
    rows = []
    for k in np.random.default_rng(1).permutation(x.size):
        j, i = divmod(k, nx)
        v = (lambda a: a if found[j, i] else np.nan)
        rows.append([x[j, i], y[j, i], 0.0, int(reachable[j, i] and found[j, i]),
                     int(stable[j, i] and found[j, i]),
                     "converged" if reachable[j, i] else ("out_of_range" if found[j, i]
                                                          else "singular"),
                     v(1e-3), v(-1e-3), v(0.0), v(0.002 + 0.001 * r[j, i]),
                     v((1.0 if stable[j, i] else -1.0) * 100 * (2 - r[j, i] / 2)),
                     v(1e-3 / (1 + 10 * r[j, i] ** 2)), v(2e-8 * (1 + 30 * r[j, i] ** 3)),
                     v(1e-6 * (1 + r[j, i])), np.nan, np.nan])
    with open(path, "w") as f:
        f.write(MAP_COLUMNS + "\n")
        for row in rows:
            f.write(",".join(str(c) for c in row) + "\n")
    return path


def test_read_map_makes_the_grid_from_any_row_order(tmp_path):
    m = pcr.plot.read_map(small_map(tmp_path / "map.csv"))
    assert m["x"].shape == (14,) and m["y"].shape == (12,) and np.all(np.diff(m["x"]) > 0)
    assert m["reachable"].dtype == bool and m["reachable"].shape == (12, 14)
    assert m["status"][-1, -1] == "singular" and np.isnan(m["max_strain"][-1, -1])
    j, i = 3, 5
    assert m["position_3sigma"][j, i] == pytest.approx(
        2e-8 * (1 + 30 * (np.hypot(m["x"][i], m["y"][j]) / 5e-3) ** 3))
    with pytest.raises(ValueError, match="grid"):
        pcr.plot.read_map({"x": [0.0, 1.0, 1.0], "y": [0.0, 0.0, 1.0], "theta": [0.0] * 3})


def test_plot_map_shows_the_data_with_units_marks_and_home(robot, tmp_path):
    csv = small_map(tmp_path / "map.csv")
    m = pcr.plot.read_map(csv)
    fig = pcr.plot.plot_map(csv, "position_3sigma", robot, path=tmp_path / "p3.png")
    check_png(tmp_path / "p3.png")
    ax, bar = fig.axes
    assert "(mm)" in ax.get_xlabel() and "(mm)" in ax.get_ylabel() and ax.get_aspect() == 1.0
    assert "µm" in bar.get_ylabel()
    mesh = ax.collections[0]
    values = m["position_3sigma"][np.isfinite(m["max_strain"])] * 1e6  # every equilibrium
    assert isinstance(mesh.norm, matplotlib.colors.LogNorm)  # 2.5 decades
    assert mesh.norm.vmin == pytest.approx(values.min()) and mesh.norm.vmax == pytest.approx(
        values.max())
    shown = texts(fig)
    assert robot.name in ax.get_title() and "3σ position error" in ax.get_title()
    for mark in ("workspace border", "outside the stroke", "unstable", "no equilibrium (IK: "
                 "singular)", "home (q = 0)"):
        assert mark in shown, mark
    # Home is drawn where FK puts the platform at q = 0.
    home = robot.forward(np.zeros(robot.num_limbs)).pose
    marker = [line for line in ax.get_lines() if line.get_label().startswith("home")][0]
    assert marker.get_xdata()[0] == pytest.approx(home.x * 1e3)

    # A linear scale when the values span less than a decade; the margin of stable ones only.
    fig = pcr.plot.plot_map(m, "max_strain", name="my robot")
    mesh = fig.axes[0].collections[0]
    strain = m["max_strain"][np.isfinite(m["max_strain"])] * 100
    assert type(mesh.norm) is matplotlib.colors.Normalize
    assert (mesh.norm.vmin, mesh.norm.vmax) == pytest.approx((strain.min(), strain.max()))
    assert "%" in fig.axes[1].get_ylabel() and fig.axes[0].get_title().startswith("my robot: ")
    fig = pcr.plot.plot_map(m, "stability_margin")
    margin = m["stability_margin"][m["stable"] & np.isfinite(m["max_strain"])]
    assert fig.axes[0].collections[0].norm.vmin == pytest.approx(margin.min()) and margin.min() > 0
    with pytest.raises(ValueError, match="no value"):
        pcr.plot.plot_map(m, "worst_position")
    with pytest.raises(ValueError, match="quantity"):
        pcr.plot.plot_map(m, "colour")
    before = csv.read_bytes()
    with pytest.raises(ValueError, match="input"):
        pcr.plot.plot_map(csv, "singularity", path=csv)
    assert csv.read_bytes() == before


def test_trajectory_errors_are_magnified_by_the_printed_factor(tmp_path):
    t = np.linspace(0, 2 * np.pi, 24, endpoint=False)
    commanded = np.column_stack([1.5e-3 * np.cos(t), 1.5e-3 * np.sin(t), np.zeros_like(t)])
    error = 2e-6 * np.column_stack([np.cos(2 * t), np.sin(3 * t), 1e-1 * np.sin(t)])
    fig = pcr.plot.plot_trajectory_accuracy(commanded, commanded + error, name="bot",
                                            label="circle, test", path=tmp_path / "c.png")
    check_png(tmp_path / "c.png")
    ax_path, ax_p, ax_t = fig.axes
    arrows = ax_path.collections[0]
    k = 1 / arrows.scale
    largest = np.hypot(error[:, 0], error[:, 1]).max()
    assert 0.05 * 3e-3 <= k * largest <= 0.15 * 3e-3  # about a tenth of the path
    assert f"× {k:,.0f}".replace(",", " ") in texts(fig)
    assert np.allclose(arrows.U, error[:, 0] * 1e3) and np.allclose(arrows.V, error[:, 1] * 1e3)
    assert ax_path.get_aspect() == 1.0 and "(mm)" in ax_path.get_xlabel()
    assert "(µm)" in ax_p.get_ylabel() and "(µrad)" in ax_t.get_ylabel()
    assert np.allclose(ax_p.get_lines()[0].get_ydata(), np.hypot(error[:, 0], error[:, 1]) * 1e6)
    assert fig.texts[0].get_text().startswith("bot: circle, test")
    fig = pcr.plot.plot_trajectory_accuracy(commanded, commanded + error, magnification=300)
    assert fig.axes[0].collections[0].scale == pytest.approx(1 / 300) and "× 300" in texts(fig)
    # Cycles per pose: the barycentres are compared, the repeatability shown; nm when small.
    cycles = commanded[:, None, :] + 1e-9 * np.random.default_rng(2).normal(size=(24, 5, 3))
    fig = pcr.plot.plot_trajectory_accuracy(commanded, cycles)
    assert "(nm)" in fig.axes[1].get_ylabel() and "repeatability RP_l" in texts(fig)


def test_trajectory_from_the_accuracy_csv(tmp_path):
    rows = ["pose,x_c,y_c,theta_c,x_bar,y_bar,theta_bar,cycles,ap_x,ap_y,ap_p,ap_theta,l_bar,"
            "s_l,rp_l,s_theta,rp_theta"]
    for k, (x, y) in enumerate([(-1e-3, -1e-3), (1e-3, -1e-3), (1e-3, 1e-3), (-1e-3, 1e-3)]):
        rows.append(f"{k},{x},{y},0,{x + 3e-9 * k},{y - 1e-9},{2e-7 * k},3,0,0,0,0,0,0,"
                    f"{2e-8 + 1e-9 * k},0,0")
    (tmp_path / "a.csv").write_text("\n".join(rows) + "\n")
    fig = pcr.plot.plot_trajectory_accuracy(tmp_path / "a.csv")
    e_p = np.hypot(3e-9 * np.arange(4), 1e-9)
    assert np.allclose(fig.axes[1].get_lines()[0].get_ydata(), e_p * 1e9)
    assert np.allclose(fig.axes[1].get_lines()[1].get_ydata(), (2e-8 + 1e-9 * np.arange(4)) * 1e9)


def test_calibration_errors_from_the_demo_csv(tmp_path):
    lines = ["set,configuration,model,e_p,e_theta"]
    for s, count in (("calibration", 6), ("validation", 3)):
        for model, scale in (("nominal", 1e-5), ("identified", 1e-8)):
            lines += [f"{s},{j},{model},{scale * (j + 1)},{scale * 30}" for j in reversed(range(
                count))]
    (tmp_path / "e.csv").write_text("\n".join(lines) + "\n")
    fig = pcr.plot.plot_calibration_errors(calibration=tmp_path / "e.csv", name="bot")
    assert len(fig.axes) == 4 and fig.texts[0].get_text().startswith("bot: ")
    assert "(µm)" in fig.axes[0].get_ylabel() and "(µrad)" in fig.axes[1].get_ylabel()
    nominal = fig.axes[0].get_lines()[0]
    assert np.allclose(nominal.get_ydata(), 1e-5 * np.arange(1, 7) * 1e6)
    assert len(fig.axes[2].get_lines()[1].get_ydata()) == 3


def test_demo_figures_and_their_page(demo_output, tmp_path):
    import shutil
    import subprocess
    import sys

    d = tmp_path / "demo"
    shutil.copytree(demo_output, d)
    r = subprocess.run([sys.executable, "-m", "pcr.plot", str(d)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    names = {"robot", "calibration-errors", "accuracy-square-nominal", "accuracy-square-identified",
             "accuracy-circle-nominal", "accuracy-circle-identified", "map-position-3sigma",
             "map-stability-margin", "map-singularity", "map-max-strain"}
    assert {p.stem for p in (d / "figures").glob("*.png")} == names
    for p in (d / "figures").glob("*.png"):
        check_png(p)
    page = (d / "figures.md").read_text()
    for name in names:
        assert f"(figures/{name}.png)" in page
    # The map's colour bar covers the CSV's values over the positions with an equilibrium.
    m = pcr.plot.read_map(d / "map-identified.csv")
    fig = pcr.plot.plot_map(d / "map-identified.csv", "position_3sigma", d / "identified.json")
    values = m["position_3sigma"][np.isfinite(m["max_strain"])] * 1e6
    norm = fig.axes[0].collections[0].norm
    assert (norm.vmin, norm.vmax) == pytest.approx((values.min(), values.max()))
    assert "femto-3pf (identified)" in fig.axes[0].get_title()
    r = subprocess.run([sys.executable, "-m", "pcr.plot", str(tmp_path)], capture_output=True,
                       text=True)
    assert r.returncode == 2 and "not a `pcr demo` output" in r.stderr


# ---- a spatial robot's demo: data/spatial-demo (its README says how it was made) -------------

SPATIAL_DEMO = pathlib.Path(__file__).parent / "data" / "spatial-demo"
SPATIAL_FIGURES = {"robot", "sensitivity", "calibration-errors", "accuracy-square",
                   "accuracy-circle", "accuracy-helix"}


def csv_columns(path):
    """The CSV's columns as float arrays (str where not numbers), read here, not by pcr.plot."""
    import csv
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    out = {}
    for name in rows[0]:
        try:
            out[name] = np.array([float(r[name]) for r in rows])
        except ValueError:
            out[name] = np.array([r[name] for r in rows])
    return out


@pytest.fixture
def spatial_demo(tmp_path):
    import shutil
    d = tmp_path / "spatial-demo"
    shutil.copytree(SPATIAL_DEMO, d)
    return d


def test_spatial_demo_figures_and_their_page(spatial_demo):
    import hashlib
    import subprocess
    import sys

    d = spatial_demo
    before = {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in d.iterdir()}
    r = subprocess.run([sys.executable, "-m", "pcr.plot", str(d)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert {p.stem for p in (d / "figures").glob("*.png")} == SPATIAL_FIGURES
    for p in (d / "figures").glob("*.png"):
        check_png(p)
    page = (d / "figures.md").read_text()
    for name in SPATIAL_FIGURES:
        assert f"(figures/{name}.png)" in page
    assert page.startswith("# pcr demo: figures of continuum-stewart-gough (virtual robot)")
    assert "Table 2" in page and "Table 3" in page and "Table 4" in page
    # Nothing the demo wrote changed; report.md links the page.
    assert {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in d.iterdir()
            if p.name in before} == before
    assert "[figures.md](figures.md)" in (d / "report.md").read_text()


def test_spatial_robot_figure_starts_each_rod_at_its_hole(spatial_demo):
    from pcr.plot._demo import _spatial_robot_figure

    robot = pcr.Robot.load(spatial_demo / "identified.json")
    fig = _spatial_robot_figure(spatial_demo, robot, None)
    ax = fig.axes[0]
    assert ax.name == "3d" and "4 configurations" in ax.get_title()  # home and the 3 farthest
    with open(spatial_demo / "identified.json") as f:
        holes = np.array([rod["A"] for rod in json.load(f)["rods"]]) * 1e3  # mm
    rods = [line for line in ax.get_lines() if line.get_label().startswith("rod ")]
    assert len(rods) == len(holes)  # one labelled line per rod (the last configuration)
    for line, hole in zip(rods, holes):
        start = np.array([a[0] for a in line.get_data_3d()])
        assert np.allclose(start, hole, atol=1e-6), (start, hole)


def test_spatial_sensitivity_bars_are_the_ranking(spatial_demo):
    c = csv_columns(spatial_demo / "sensitivity.csv")
    order = np.argsort(c["rank"])
    fig = pcr.plot.plot_sensitivity(spatial_demo / "sensitivity.csv", floor=(2e-7, 2e-6))
    ax = fig.axes[0]
    widths = np.array([bar.get_width() for bar in ax.patches])
    assert np.allclose(widths, c["position_error_m"][order] * 1e6)  # um, most influential first
    assert [t.get_text() for t in ax.get_yticklabels()] == list(c["param"][order])
    assert ax.get_xscale() == "log" and "(µm)" in ax.get_xlabel()
    assert ax.get_lines()[0].get_xdata()[0] == pytest.approx(0.2)  # the floor, um


def test_spatial_calibration_errors_per_configuration(spatial_demo):
    with open(spatial_demo / "report.json") as f:
        noise = json.load(f)["noise"]
    floor = (np.sqrt(3) * noise["position_m"], np.sqrt(3) * noise["angle_rad"])
    fig = pcr.plot.plot_calibration_errors(calibration=spatial_demo / "calibration-errors.csv",
                                           floor=floor)
    rows = {s: len(csv_columns(spatial_demo / f"{s}.csv")["q1"])
            for s in ("calibration", "validation")}
    for axes, s in ((fig.axes[:2], "calibration"), (fig.axes[2:], "validation")):
        for ax in axes:
            nominal, identified, noise_floor = ax.get_lines()
            assert len(nominal.get_xdata()) == len(identified.get_xdata()) == rows[s]
        assert axes[0].get_lines()[2].get_ydata()[0] == pytest.approx(floor[0] * 1e6)
    assert "e_angle" in fig.axes[1].get_ylabel()


@pytest.mark.parametrize("path_name", ["square", "circle", "helix"])
def test_spatial_path_in_3d_and_its_accuracy(spatial_demo, path_name):
    sources = [spatial_demo / f"accuracy-{path_name}-{m}.csv" for m in ("nominal", "identified")]
    fig = pcr.plot.plot_spatial_path_accuracy(*sources, label=path_name)
    ax3, ax_p, ax_a = fig.axes
    c = csv_columns(sources[0])
    commanded = np.array(ax3.get_lines()[0].get_data_3d()).T
    assert len(commanded) == len(c["pose"])  # every pose of the CSV
    assert np.allclose(commanded, np.column_stack([c["x_c"], c["y_c"], c["z_c"]]) * 1e3)
    for k, source in enumerate(sources):  # AP_p: the barycentre's distance to the command
        m = csv_columns(source)
        distance = np.linalg.norm(np.column_stack([m["x_bar"] - m["x_c"], m["y_bar"] - m["y_c"],
                                                   m["z_bar"] - m["z_c"]]), axis=1)
        assert np.allclose(ax_p.get_lines()[2 * k].get_ydata(), distance * 1e6, rtol=1e-6)
    assert "(µm)" in ax_p.get_ylabel() and fig.texts[0].get_text().startswith(path_name)


def test_a_spatial_demo_without_its_errors_file_draws_the_rest(spatial_demo):
    (spatial_demo / "calibration-errors.csv").unlink()
    written = pcr.plot.demo_figures(spatial_demo)
    assert {pathlib.Path(p).stem for p in written if p.endswith(".png")} == \
        SPATIAL_FIGURES - {"calibration-errors"}
    assert "no calibration-errors.csv" in (spatial_demo / "figures.md").read_text()
