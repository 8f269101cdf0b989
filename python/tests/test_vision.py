"""Measurement from images (pcr::vision): image and file round trips, bad files named, and a
rendered robot measured back against the truth used to render it."""
import os

import numpy as np
import pytest

import pcr

pytestmark = pytest.mark.skipif(not getattr(pcr, "has_vision", False),
                                reason="pcr::vision not built")

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))


def small_camera():
    # 1700 x 1700 px, 100 um/px at 0.5 m (the robot spans ~150 mm), some radial distortion
    K = np.array([[5000.0, 0, 851.3], [0, 5000.0, 848.9], [0, 0, 1]])
    return pcr.Camera(1700, 1700, K, [-0.1, 0.05, 0, 0, 0])


def test_image_round_trip(tmp_path):
    v, u = np.mgrid[0:40, 0:60]
    image = ((u + 2 * v) / (59 + 78)).astype(np.float32)
    for bits, tol in ((8, 0.5 / 255 + 1e-6), (16, 0.5 / 65535 + 1e-7)):
        f = tmp_path / f"grad{bits}.png"
        pcr.write_png(str(f), image, bits=bits)
        back = pcr.read_image(str(f))
        assert back.dtype == np.float32 and back.shape == (40, 60)
        assert np.max(np.abs(back - image)) <= tol
    with pytest.raises(FileNotFoundError, match="missing.png"):
        pcr.read_image(str(tmp_path / "missing.png"))
    with pytest.raises(ValueError, match="bits"):
        pcr.write_png(str(tmp_path / "x.png"), image, bits=12)
    with pytest.raises(ValueError):
        pcr.write_png(str(tmp_path / "x.png"), np.zeros(5))


def test_camera_and_mounts_files(tmp_path):
    cam = small_camera()
    f = tmp_path / "camera.yaml"
    cam.save(str(f))
    back = pcr.load_camera(str(f))
    assert (back.width, back.height) == (1700, 1700)
    np.testing.assert_allclose(back.K, cam.K, rtol=1e-12)
    np.testing.assert_allclose(back.distortion, cam.distortion, rtol=1e-12)
    # a point on the optical axis projects onto the principal point
    np.testing.assert_allclose(cam.project([0, 0, 1.0]), [851.3, 848.9], atol=1e-12)
    bad = tmp_path / "bad_camera.yaml"
    bad.write_text("%YAML:1.0\n---\nimage_width: 10\n")
    with pytest.raises(ValueError, match="bad_camera.yaml"):
        pcr.load_camera(str(bad))

    layout = pcr.default_mounts()
    assert layout.num_limbs == 3 and len(layout) == 6
    from_file = pcr.load_mounts(os.path.join(ROOT, "data", "mounts-femto-3pf.json"))
    assert [m["id"] for m in from_file.mounts] == [m["id"] for m in layout.mounts]
    assert {m["role"] for m in layout.mounts} == {"proximal", "distal"}
    bad = tmp_path / "bad_mounts.json"
    bad.write_text('{"format": "pcr-mounts", "version": 1, "mounts": [{"name": "A1"}]}')
    with pytest.raises(ValueError, match="bad_mounts.json"):
        pcr.load_mounts(str(bad))


def rigid_fit(src, dst):
    """Least-squares 2-D rotation + translation taking src onto dst (Kabsch), and its angle."""
    src, dst = np.asarray(src), np.asarray(dst)
    cs, cd = src.mean(axis=0), dst.mean(axis=0)
    h = (src - cs).T @ (dst - cd)
    angle = np.arctan2(h[0, 1] - h[1, 0], h[0, 0] + h[1, 1])
    R = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
    return (lambda p: (R @ (np.asarray(p) - cs)) + cd), angle


def test_measure_rendered_robot_against_truth(robot):
    rng = np.random.default_rng(11)
    design = robot
    truth = design.copy()
    for limb in truth.limbs:
        limb.A = limb.A + rng.uniform(-1e-3, 1e-3, 2)
        limb.alpha += rng.uniform(-0.02, 0.02)
        limb.B = limb.B + rng.uniform(-1e-3, 1e-3, 2)
        limb.beta += rng.uniform(-0.02, 0.02)
    layout = pcr.default_mounts().without_uncertainty()  # the tags sit exactly as declared
    cam = small_camera()
    tags = pcr.mount_tags(truth, layout, platform=(1e-3, -5e-4, 0.01))
    assert len(tags) == 6
    image = pcr.render_robot(truth, layout, camera=cam, height=0.5, tilt_x=0.01, tilt_y=-0.02,
                             platform=(1e-3, -5e-4, 0.01), supersampling=2, blur=0.7,
                             noise=0.01, seed=3)
    assert image.shape == (1700, 1700) and image.dtype == np.float32
    m = pcr.measure_robot(image, layout, cam, design, source="rendered.png")
    assert len(m.limbs) == 3 and m.corner_rms_px < 0.5

    # Reference: the truth registered onto the design the way metrology does (best-fit rigid
    # transforms of the A_i and of the B_i), computed here independently.
    to_w, rot_w = rigid_fit([l.A for l in truth.limbs], [l.A for l in design.limbs])
    to_p, rot_p = rigid_fit([l.B for l in truth.limbs], [l.B for l in design.limbs])
    for lt, lm in zip(truth.limbs, m.limbs):
        assert np.all(lm["A_halfwidth"] > 0) and np.all(lm["A_halfwidth"] < 50e-6)
        assert np.all(np.abs(lm["A"] - to_w(lt.A)) <= lm["A_halfwidth"])
        assert np.all(np.abs(lm["B"] - to_p(lt.B)) <= lm["B_halfwidth"])
        assert abs(wrap(lm["alpha"] - (lt.alpha + rot_w))) <= lm["alpha_halfwidth"]
        assert abs(wrap(lm["beta"] - (lt.beta + rot_p))) <= lm["beta_halfwidth"]
        assert lm["gamma"] is None

    measured = pcr.measured_description(design, m)
    assert isinstance(measured, pcr.Robot)
    for i, lm in enumerate(m.limbs):
        np.testing.assert_array_equal(measured.limbs[i].A, lm["A"])
        assert measured.limbs[i].beta == lm["beta"]
        np.testing.assert_array_equal(measured.uncertainty.limbs[i].A, lm["A_halfwidth"])
        assert measured.limbs[i].l == design.limbs[i].l  # not measured: kept from the design

    with pytest.raises(ValueError, match="blank.png"):
        pcr.measure_robot(np.full((1700, 1700), 0.5, np.float32), layout, cam, design,
                          source="blank.png")
    with pytest.raises(ValueError, match="small.png"):
        pcr.measure_robot(image[:900], layout, cam, design, source="small.png")


def wrap(a):
    return np.arctan2(np.sin(a), np.cos(a))


def test_actuator_sweep_measures_gamma(robot):
    # The truth's actuator 0 moves its clamp 12 mrad off the rod's direction: the sweep of its
    # proximal tag over a 1 mm stroke must find that angle within the half-width it reports.
    design = robot
    truth = design.with_limb(0, gamma=0.012)
    layout = pcr.default_mounts().without_uncertainty()
    cam = small_camera()
    render = dict(camera=cam, height=0.5, tilt_x=0.01, supersampling=2, blur=0.7, noise=0.01)
    home = pcr.measure_robot(pcr.render_robot(truth, layout, seed=1, **render), layout, cam,
                             design, source="home.png")
    strokes = np.linspace(-0.5e-3, 0.5e-3, 6)
    images = [pcr.render_robot(truth, layout, q=[q, 0.0, 0.0], seed=2 + k, **render)
              for k, q in enumerate(strokes)]
    sweep = pcr.measure_sweep(images, 0, layout, cam, home)
    assert sweep.centres.shape == (6, 2)
    # The tag centre moved by the stroke along the line (the plane's scale is the camera's).
    travel = np.linalg.norm(sweep.centres[-1] - sweep.centres[0])
    assert abs(travel - 1e-3) < 5e-6
    assert 0 < sweep.gamma_halfwidth < 5e-3
    assert abs(sweep.gamma - 0.012) <= sweep.gamma_halfwidth
    assert home.limbs[0]["gamma"] == sweep.gamma
    assert pcr.measured_description(design, home).limbs[0].gamma == sweep.gamma

    with pytest.raises(ValueError, match="at least 3 images"):
        pcr.measure_sweep(images[:2], 0, layout, cam, home)
    with pytest.raises(ValueError, match="sources"):
        pcr.measure_sweep(images, 0, layout, cam, home, sources=["a.png"])
    with pytest.raises(ValueError, match="blank step"):
        pcr.measure_sweep(images[:3] + [np.full((1700, 1700), 0.5, np.float32)], 0, layout, cam,
                          home, sources=["s0", "s1", "s2", "blank step"])


def test_camera_from_rendered_chessboards(tmp_path):
    # The camera that rendered the boards, recovered by calibrate_camera (as `pcr camera`).
    K = np.array([[900.0, 0, 402], [0, 905.0, 297], [0, 0, 1]])
    truth = pcr.Camera(800, 600, K, [-0.2, 0.1, 0, 0, 0])
    views = [(0.0, 0.0, 0.0), (0.3, 0.0, 0.05), (-0.3, 0.1, 0.1), (0.1, 0.35, 0.15),
             (0.0, -0.35, 0.2), (0.25, 0.25, 0.25)]
    paths = []
    for k, (tilt_x, tilt_y, angle) in enumerate(views):
        image = pcr.render_chessboard(camera=truth, cols=9, rows=6, square=0.008,
                                      board_pose=(0, 0, angle), height=0.12, tilt_x=tilt_x,
                                      tilt_y=tilt_y, supersampling=3, blur=0.7)
        paths.append(str(tmp_path / f"board{k}.png"))
        pcr.write_png(paths[-1], image)
    noise = str(tmp_path / "noise.png")  # an image without a board: rejected, named
    pcr.write_png(noise, np.random.default_rng(5).uniform(0.2, 0.8, (600, 800)))
    result = pcr.calibrate_camera(paths + [noise], cols=9, rows=6, square=0.008)
    assert result.used == paths and result.rejected == [noise]
    assert result.rms_px < 0.5
    cam = result.camera
    assert (cam.width, cam.height) == (800, 600)
    np.testing.assert_allclose(np.diag(cam.K)[:2], [900, 905], atol=9)
    np.testing.assert_allclose(cam.K[:2, 2], [402, 297], atol=8)
    assert abs(cam.distortion[0] + 0.2) < 0.05
    with pytest.raises(ValueError, match="at least 3"):
        pcr.calibrate_camera(paths[:2] + [noise], cols=9, rows=6, square=0.008)
    with pytest.raises(FileNotFoundError, match="missing.png"):
        pcr.calibrate_camera(paths + [str(tmp_path / "missing.png")], square=0.008)
