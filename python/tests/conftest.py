"""Fixtures of the Python tests: the hovs executable and the module from the same build, and small data sets made
by the CLI (a rendered calibration set and its calibration), so that the module is compared with the CLI on the
same inputs."""

import os
import pathlib
import subprocess

import pytest

SOURCE_DIR = pathlib.Path(os.environ.get("HOVS_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2]))
BINARY = pathlib.Path(os.environ.get("HOVS_BINARY", SOURCE_DIR / "build" / "apps" / "hovs"))


def run_hovs(*args, cwd=None, display=False):
    """Runs the CLI; fails the test with its output when it does not exit 0. display: the command draws figures
    with VTK, which needs an X display (xvfb-run -a when none is set)."""
    prefix = ["xvfb-run", "-a"] if display and not os.environ.get("DISPLAY") else []
    p = subprocess.run([*prefix, str(BINARY), *map(str, args)], capture_output=True, text=True, cwd=cwd)
    if p.returncode != 0:
        pytest.fail(f"hovs {' '.join(map(str, args))} exited {p.returncode}:\n{p.stdout}\n{p.stderr}")
    return p


@pytest.fixture(scope="session")
def source_dir():
    return SOURCE_DIR


@pytest.fixture(scope="session")
def dataset(tmp_path_factory):
    """Six frames of the reference calibration scene at 1/5 of the resolution (550 x 440), one sample per pixel,
    with every ground-truth channel (the export test checks the world point P)."""
    out = tmp_path_factory.mktemp("data") / "dataset"
    run_hovs("dataset", "--scene", SOURCE_DIR / "scenes" / "reference_calibration.yaml", "--downscale", 5,
             "--samples", 1, "-n", 6, "--seed", 3, "--truth", "all", "--out", out)
    return out / "dataset.json"


@pytest.fixture(scope="session")
def calibration(dataset, tmp_path_factory):
    """`hovs calibrate` on the exact corners of the dataset: calibration.json, calib_results.txt, unified.yaml."""
    out = tmp_path_factory.mktemp("calib") / "calibration"
    run_hovs("calibrate", "--dataset", dataset, "--truth-corners", "--out", out)
    return out
