"""Sketch tools (atelier.sketch; systems/sketch, seed 001 section 5): a cut
through a sphere along a plane, picked below, leaves the part above the
plane (about half the area), the same file bytes as `atelier sketch` for the
same mesh and stroke file, and ValueError/OSError with the engine's message
for bad strokes, bad files and bad arrays."""
import json

import numpy as np
import pytest

import atelier
from conftest import HALF, SIZE, ortho_camera, px, run_cli



def sphere(lon=32, lat=16):
    """A unit uv sphere: poles, quads between rings, outward faces."""
    v = [[0.0, 0.0, 1.0]]
    for i in range(1, lat):
        th = np.pi * i / lat
        for j in range(lon):
            ph = 2 * np.pi * j / lon
            v.append([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)])
    v.append([0.0, 0.0, -1.0])
    ring = lambda i, j: 1 + (i - 1) * lon + j % lon  # noqa: E731
    f = [[0, ring(1, j), ring(1, j + 1)] for j in range(lon)]
    f += [[ring(i, j), ring(i + 1, j), ring(i + 1, j + 1), ring(i, j + 1)] for i in range(1, lat - 1) for j in range(lon)]
    f += [[len(v) - 1, ring(lat - 1, j + 1), ring(lat - 1, j)] for j in range(lon)]
    return np.array(v), f



def strokes(cut_y=0.03):
    return {
        "camera": ortho_camera(),
        "strokes": [
            {"points": [px(-1.4, cut_y), px(1.4, cut_y)], "tool": "cut", "through": True},
            {"points": [px(0.0, -0.8)], "tool": "pick"},
        ],
    }


def area(v, faces):
    total = 0.0
    for p in (faces.tolist() if not isinstance(faces, list) else [list(x) for x in faces]):
        for j in range(1, len(p) - 1):
            total += 0.5 * np.linalg.norm(np.cross(v[p[j]] - v[p[0]], v[p[j + 1]] - v[p[0]]))
    return total


def test_a_plane_cut_leaves_the_part_above_the_plane():
    v, f = sphere()
    mesh, rep = atelier.sketch((v, f), strokes(0.03))
    rv, rf = mesh
    assert rep["failed"] == 0 and rep["tools"][0]["tool"] == "cut" and rep["tools"][0]["ok"]
    # Everything left is above the cutting plane y = 0.03 (the cut's new
    # vertices lie on it), and the removed area is what is gone.
    assert rv.min(axis=0)[1] > 0.03 - 1e-9
    full, left = area(v, f), area(rv, rf)
    assert 0.44 < left / full < 0.5
    assert rep["tools"][0]["removed_area"] == pytest.approx(full - left, rel=1e-9)
    mesh.validate()
    # The result's arrays are read-only views onto the engine's model (zero copy).
    assert np.shares_memory(mesh.vertices, mesh.vertices) and not rv.flags.writeable


def test_same_file_as_the_cli(scratch):
    v, f = sphere()
    atelier.write_mesh(scratch / "sphere.obj", v, f)
    (scratch / "strokes.json").write_text(json.dumps(strokes(-0.21)))
    run_cli("--threads", 1, "sketch", "--mesh", scratch / "sphere.obj", "--strokes", scratch / "strokes.json",
            "--out", scratch / "cli.obj", "--json", scratch / "cli.json")
    mesh, rep = atelier.sketch(atelier.read_mesh(scratch / "sphere.obj"), scratch / "strokes.json", threads=2)
    atelier.write_mesh(scratch / "py.obj", mesh)
    assert (scratch / "py.obj").read_bytes() == (scratch / "cli.obj").read_bytes()
    theirs = json.loads((scratch / "cli.json").read_text())
    assert rep["tools"][0]["removed_area"] == theirs["tools"][0]["removed_area"]
    # A dict gives what its file gives.
    again, _ = atelier.sketch(atelier.read_mesh(scratch / "sphere.obj"), strokes(-0.21))
    assert again.vertices.tobytes() == mesh.vertices.tobytes()


def test_bad_strokes_files_and_arrays_raise_with_the_engines_message(scratch):
    v, f = sphere(12, 6)
    bad = strokes()
    bad["strokes"][0]["points"][1][0] = float("nan")
    with pytest.raises(ValueError, match="non-finite|NaN"):
        atelier.sketch((v, f), bad)
    missing = strokes()
    del missing["strokes"][0]["points"]
    with pytest.raises(ValueError, match='at /strokes/0: missing key "points"'):
        atelier.sketch((v, f), missing)
    (scratch / "syntax.json").write_text('{\n  "camera": [}')
    with pytest.raises(ValueError, match=r"syntax\.json:2:"):
        atelier.sketch((v, f), scratch / "syntax.json")
    with pytest.raises(OSError, match="nope.json"):
        atelier.sketch((v, f), scratch / "nope.json")
    nan = v.copy()
    nan[1, 2] = np.nan
    with pytest.raises(ValueError, match="vertex 1 is not finite"):
        atelier.sketch((nan, f), strokes())
    with pytest.raises(ValueError, match="no surface named 'collar'"):
        atelier.sketch((v, f), strokes(), surfaces=["collar"])
