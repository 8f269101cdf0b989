"""Shared fixtures. The `pcr` CLI comes from $PCR_CLI (set by ctest), else build*/apps/pcr."""
import glob
import os
import shutil
import subprocess

import matplotlib
import pytest

matplotlib.use("Agg")

import pcr  # noqa: E402

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))


def pytest_report_header(config):
    return f"pcr {pcr.__version__} from {os.path.dirname(pcr.__file__)}"


def pytest_configure(config):
    # ctest runs the marked tests apart (python/CMakeLists.txt): -m cluster, and -m "not cluster"
    config.addinivalue_line("markers", "cluster: starts a one-node Slurm cluster on this machine "
                            "(root, the slurm-wlm and munge packages: test_cluster.py)")



def _find_cli():
    path = os.environ.get("PCR_CLI")
    if path:
        return path
    for candidate in [os.path.join(ROOT, "build", "apps", "pcr")] + sorted(
            glob.glob(os.path.join(ROOT, "build*", "apps", "pcr"))):
        if os.access(candidate, os.X_OK):
            return candidate
    return shutil.which("pcr")


@pytest.fixture(scope="session")
def cli():
    path = _find_cli()
    if os.environ.get("PCR_CLI") and not os.access(path, os.X_OK):
        pytest.fail(f"PCR_CLI={path} is not an executable")
    if not path or not os.access(path, os.X_OK):
        pytest.skip("the pcr CLI was not found (set PCR_CLI)")
    return path


@pytest.fixture
def robot():
    return pcr.Robot.default()


@pytest.fixture(scope="session")
def demo_output(cli, tmp_path_factory):
    """A small `pcr demo` output directory (no vision; few configurations, cycles and poses)."""
    if " demo " not in subprocess.run([cli, "--help"], capture_output=True, text=True).stdout:
        pytest.skip("pcr demo is not built (it needs pcr::calib)")
    out = tmp_path_factory.mktemp("demo") / "out"
    result = subprocess.run([cli, "demo", "--quiet", "--no-vision", "--output", str(out),
                             "--calibration", "20", "--validation", "4", "--repeat", "3",
                             "--poses", "4"], capture_output=True, text=True, timeout=600)
    assert result.returncode == 0, result.stderr
    return out
