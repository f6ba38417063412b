"""Flattening (atelier.flatten; systems/pattern): a planar patch flattens
isometrically (E_L < 1e-8, no flips, every edge keeps its length), a
spherical cap is distorted but not flipped, the same distortion figures as
`atelier flatten --json` for the same file (bit for bit), and a ValueError
with the engine's message for bad input."""
import json

import numpy as np
import pytest

import atelier
from conftest import run_cli


def grid(n=8, lift=None):
    """An n x n grid of quads over [0, 1]^2, unevenly spaced; z = lift(x, y)."""
    s = np.linspace(0, 1, n + 1) ** 1.3
    v = np.array([[x, y, 0.0] for y in s for x in s])
    if lift is not None:
        v[:, 2] = lift(v[:, 0], v[:, 1])
    f = np.array([[j * (n + 1) + i, j * (n + 1) + i + 1, (j + 1) * (n + 1) + i + 1, (j + 1) * (n + 1) + i]
                  for j in range(n) for i in range(n)])
    return v, f


def edges(faces):
    e = set()
    for p in faces.tolist():
        for a, b in zip(p, p[1:] + p[:1]):
            e.add((min(a, b), max(a, b)))
    return np.array(sorted(e))


def test_planar_patch_flattens_isometrically():
    v, f = grid()
    uv, pieces = atelier.flatten((v, f))
    assert len(pieces) == 1
    d = pieces[0]["distortion"]
    assert d["length_error"] < 1e-8 and d["area_error"] < 1e-8
    assert d["flipped"] == 0 and d["boundary_crossings"] == 0
    assert uv.shape == (len(v), 2)
    e = edges(f)
    l3 = np.linalg.norm(v[e[:, 0]] - v[e[:, 1]], axis=1)
    l2 = np.linalg.norm(uv[e[:, 0]] - uv[e[:, 1]], axis=1)
    assert np.abs(l2 - l3).max() < 1e-8
    assert sorted(pieces[0]["vertices"].tolist()) == list(range(len(v)))


def test_curved_patch_is_distorted_not_flipped():
    v, f = grid(10, lift=lambda x, y: 0.6 * (x - 0.5) ** 2 + 0.6 * (y - 0.5) ** 2)  # a bowl: not developable
    uv, pieces = atelier.flatten((v, f))
    d = pieces[0]["distortion"]
    assert d["flipped"] == 0 and d["boundary_crossings"] == 0
    assert 1e-6 < d["length_error"] < 0.1
    t = pieces[0]["triangles"]
    a = uv[t[:, 1]] - uv[t[:, 0]]
    b = uv[t[:, 2]] - uv[t[:, 0]]
    signed = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
    assert (signed > 0).all() or (signed < 0).all()  # no triangle folds over (an independent flip count)


def test_same_figures_as_the_cli(scratch):
    v, f = grid(10, lift=lambda x, y: 0.3 * np.sin(3 * x) * y)
    atelier.write_mesh(scratch / "patch.obj", v, f)
    run_cli("--threads", 1, "flatten", "--mesh", scratch / "patch.obj", "--out", scratch / "out",
            "--no-strain-maps", "--json", scratch / "r.json")
    theirs = json.loads((scratch / "r.json").read_text())["pieces"]
    _, ours = atelier.flatten(atelier.read_mesh(scratch / "patch.obj"), threads=2)
    assert [p["name"] for p in ours] == [p["name"] for p in theirs]
    for o, t in zip(ours, theirs):
        assert o["distortion"] == t["distortion"]  # JSON doubles read back exactly
        assert o["solver"]["energy"] == t["solver"]["energy"]
        assert o["solver"]["iterations"] == t["solver"]["iterations"]


def test_bad_input_is_a_value_error_with_the_engines_message():
    v, f = grid(4)
    bad = v.copy()
    bad[3, 0] = np.inf
    with pytest.raises(ValueError, match="vertex 3 is not finite"):
        atelier.flatten((bad, f))
    with pytest.raises(ValueError, match="uses vertex 25"):
        atelier.flatten((v, np.where(f == 24, 25, f)))
    with pytest.raises(ValueError, match="no surface named 'sleeve'"):
        atelier.flatten((v, f), surfaces=["sleeve"])
    # A piece with a hole (the middle quad removed) is refused unless allow_holes.
    holed = np.delete(f, 5, axis=0)
    with pytest.raises(ValueError, match="hole|boundary loop"):
        atelier.flatten((v, holed))
