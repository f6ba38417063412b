"""Curve networks to surfaces (atelier.surface_from_curves; systems/curvenet,
seed 003): the wireframe of a cube becomes a closed surface of genus 0
(V - E + F = 2, every edge on two faces), the same bits as `atelier
surface` for the same curve file, and ValueError/OSError with the engine's
message for bad curves and bad files."""
import itertools

import numpy as np
import pytest

import atelier
from conftest import run_cli


def cube_curves(points=9):
    """The 12 edges of the unit cube, each a polyline of `points` points."""
    corners = [np.array(c, dtype=np.float64) for c in itertools.product((0.0, 1.0), repeat=3)]
    curves = []
    for a, b in itertools.combinations(corners, 2):
        if np.abs(a - b).sum() == 1.0:
            t = np.linspace(0.0, 1.0, points)[:, None]
            curves.append(a + t * (b - a))
    assert len(curves) == 12
    return curves


def write_curves(path, curves):
    with open(path, "w") as f:
        for i, c in enumerate(curves):
            f.write(f"CURVE {i}\n")
            for p in c:
                f.write(" ".join(repr(float(x)) for x in p) + "\n")


def euler_and_edges(faces):
    uses = {}
    for p in faces.tolist():
        for a, b in zip(p, p[1:] + p[:1]):
            k = (min(a, b), max(a, b))
            uses[k] = uses.get(k, 0) + 1
    verts = {v for p in faces.tolist() for v in p}
    return len(verts) - len(uses) + len(faces), uses


def test_cube_wireframe_gives_a_closed_genus_0_surface():
    v, f, rep = atelier.surface_from_curves(cube_curves(), levels=2)
    euler, uses = euler_and_edges(f)
    assert euler == 2
    assert set(uses.values()) == {2}  # closed: every edge on two faces
    assert rep["cycles"]["faces"] == 6 and rep["cycles"]["euler"] == 2
    assert rep["stop_rule_met"]
    # Catmull-Clark level 2: 16 quads per control quad.
    assert len(f) == 16 * rep["control_mesh"]["quads"]
    cv, cf = rep["control"]
    assert len(cf) == rep["control_mesh"]["quads"]
    # The cube's symmetry: the vertex set is mapped onto itself by x -> 1 - x
    # and by swapping x and y.
    key = lambda a: set(map(tuple, np.round(a, 9)))  # noqa: E731
    assert key(v) == key(v * [-1, 1, 1] + [1, 0, 0])
    assert key(v) == key(v[:, [1, 0, 2]])
    assert rep["distance_to_curves"]["relative_max"] < 1e-2


def test_same_bits_as_the_cli(scratch):
    curves = cube_curves(7)
    write_curves(scratch / "cube.txt", curves)
    run_cli("--threads", 1, "surface", "--curves", scratch / "cube.txt", "--levels", 1, "--out", scratch / "s.obj")
    theirs_v, theirs_f = atelier.read_mesh(scratch / "s.obj")
    ours_v, ours_f, _ = atelier.surface_from_curves(scratch / "cube.txt", levels=1, threads=2)
    assert ours_v.tobytes() == theirs_v.tobytes()
    assert np.array_equal(ours_f, theirs_f)
    # The arrays give what the file gives (repr() above writes the doubles exactly).
    arr_v, arr_f, _ = atelier.surface_from_curves(curves, levels=1)
    assert arr_v.tobytes() == ours_v.tobytes() and np.array_equal(arr_f, ours_f)


def test_bad_curves_and_files_raise_with_the_engines_message(scratch):
    curves = cube_curves()
    curves[3] = curves[3].copy()
    curves[3][4, 2] = np.nan
    with pytest.raises(ValueError, match=r"curves\[3\]: vertex 4 is not finite"):
        atelier.surface_from_curves(curves)
    with pytest.raises(ValueError, match=r"curves\[0\]: a curve needs at least 2 points"):
        atelier.surface_from_curves([np.zeros((1, 3))])
    with pytest.raises(ValueError, match="levels"):
        atelier.surface_from_curves(cube_curves(), levels=9)
    (scratch / "bad.txt").write_text("CURVE 0\n0 0 0\n1 zero 0\n")
    with pytest.raises(ValueError, match=r"bad\.txt.*2|bad\.txt.*3"):
        atelier.surface_from_curves(scratch / "bad.txt")
    with pytest.raises(OSError, match="missing.txt"):
        atelier.surface_from_curves(scratch / "missing.txt")
