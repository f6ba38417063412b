"""Shared fixtures of the binding's pytest suite (python/tests).

ctest runs each test file with Debian's /usr/bin/python3 and
PYTHONPATH=<build>/python (python/CMakeLists.txt); ATELIER_CLI is the built
CLI, ATELIER_SHARED_DATA the shared data folder, ATELIER_TMP a scratch
folder in the build tree.
"""
import os
import pathlib
import shutil
import subprocess

import numpy as np
import pytest

import atelier

SHARED = pathlib.Path(os.environ.get("ATELIER_SHARED_DATA", "../shared/data"))
MAKEHUMAN = SHARED / "makehuman"


def cli():
    """The built CLI, or a skip when the suite runs outside ctest."""
    path = os.environ.get("ATELIER_CLI")
    if not path or not os.path.exists(path):
        pytest.skip("ATELIER_CLI is not set (run the suite through ctest)")
    return path


def run_cli(*args):
    """Runs the CLI; fails the test with its output on a non-zero exit."""
    r = subprocess.run([cli(), *map(str, args)], capture_output=True, text=True)
    assert r.returncode == 0, f"atelier {' '.join(map(str, args))} exited {r.returncode}:\n{r.stdout}\n{r.stderr}"
    return r


@pytest.fixture
def scratch(request):
    """An empty folder under $ATELIER_TMP named after the test."""
    root = pathlib.Path(os.environ.get("ATELIER_TMP", "/tmp/atelier-tests")).resolve() / "python"
    d = root / request.node.name.replace("[", "_").replace("]", "_")
    shutil.rmtree(d, ignore_errors=True)
    d.mkdir(parents=True)
    return d


def curve_height(body, name):
    return float(body.curve(name)[:, 1].mean())


def demo_shorts(body):
    """The demo's shorts (apps/atelier/demo.cpp): the skin band from mid-thigh
    to 2 cm above the waist, 8 mm out."""
    y_waist = curve_height(body, "waist")
    y_thigh = curve_height(body, "thigh_left")
    y_knee = curve_height(body, "knee_left")
    return atelier.skin_band_garment(body, 0.5 * (y_thigh + y_knee), y_waist + 0.02, 0.008, 0.40, "shorts")


def top_band(body, offset=0.014):
    """A second, outer garment over the shorts' upper part (for layers)."""
    y_waist = curve_height(body, "waist")
    y_hip = curve_height(body, "hip")
    return atelier.skin_band_garment(body, y_hip - 0.03, y_waist + 0.06, offset, 0.40, "wrap")


@pytest.fixture(scope="session")
def small():
    """A coarse mannequin (level 3) with its family and the demo's shorts,
    encoded from float32 vertices (so a saved template reads back equal)."""
    mannequin = atelier.Mannequin(3)
    body = mannequin.reference()
    family = atelier.GarmentFamily(body)
    shorts_mesh = demo_shorts(body)
    v, f = shorts_mesh
    shorts = atelier.encode_garment(family, v.astype(np.float32), f, name="shorts")
    params = atelier.sample_mannequins(6, seed=11)
    bodies = mannequin.positions(params, dtype="float32")
    return {
        "mannequin": mannequin,
        "body": body,
        "family": family,
        "shorts_mesh": shorts_mesh,
        "shorts": shorts,
        "params": params,
        "bodies": bodies,
    }


# The orthographic camera of the stroke-file tests (test_sketch, test_extrude):
# it looks down -z from z = 5 and sees [-HALF, HALF]^2 on a SIZE x SIZE view.
SIZE = 800
HALF = 1.5


def px(x, y):
    """Pixel of a 3D point (x, y, *) seen by the camera below (y down)."""
    return [(x / HALF + 1) / 2 * SIZE, (1 - y / HALF) / 2 * SIZE]


def ortho_camera(n=0.1, far=10.0):
    return {
        "view": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, -5, 0, 0, 0, 1],
        "projection": [1 / HALF, 0, 0, 0, 0, 1 / HALF, 0, 0, 0, 0, -2 / (far - n), -(far + n) / (far - n), 0, 0, 0, 1],
        "viewport": [SIZE, SIZE],
    }
