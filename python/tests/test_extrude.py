"""Sketch extrusion (atelier.extrude; systems/sketch/extrude.h, seed 002): a
dome drawn on an open cup lies on the unit sphere and closes the cup
(V - E + F = 2) with the counts of the sweep, gives the same file bytes as
`atelier extrude`, and bad strokes raise with the engine's message."""
import json

import numpy as np
import pytest

import atelier
from conftest import HALF, SIZE, ortho_camera, px, run_cli

N = 24


def cup(n=N):
    """Unit circles at y = 0, -0.5, -1 and a bottom centre; open at y = 0."""
    v = [[np.cos(2 * np.pi * i / n), -0.5 * r, np.sin(2 * np.pi * i / n)] for r in range(3) for i in range(n)]
    v.append([0.0, -1.0, 0.0])
    idx = lambda r, i: r * n + i % n  # noqa: E731
    f = []
    for r in range(2):
        for i in range(n):
            f.append([idx(r, i), idx(r, i + 1), idx(r + 1, i + 1)])
            f.append([idx(r, i), idx(r + 1, i + 1), idx(r + 1, i)])
    f += [[idx(2, i), idx(2, i + 1), 3 * n] for i in range(n)]
    return np.array(v), f



def strokes(start_y=0.0, k=10):
    arc = [px(np.cos(np.pi * (1 - i / (2 * k))), start_y + np.sin(np.pi * (1 - i / (2 * k)))) for i in range(2 * k + 1)]
    return {
        "camera": ortho_camera(),
        "strokes": [
            # The rim seen edge-on: a closed stroke along it selects the whole boundary loop.
            {"points": [px(-1, 0), px(1, 0), px(-1, 0)], "tool": "extrude", "name": "rim"},
            {"points": arc, "tool": "extrude", "name": "dome"},
        ],
    }


def euler(nv, faces):
    edges = set()
    for p in faces:
        p = list(p)
        for a, b in zip(p, p[1:] + p[:1]):
            edges.add((min(a, b), max(a, b)))
    return nv - len(edges) + len(faces)


def test_dome_on_a_cup_is_on_the_sphere_and_closed():
    v, f = cup()
    mesh, rep = atelier.extrude((v, f), strokes(), optimise=False)
    assert rep["copies"] == 10 and rep["capped"] and rep["base_ring"]
    assert len(mesh.vertices) == len(v) + N * (rep["copies"] - 1) + 1
    assert len(mesh.faces) == len(f) + N * (2 * rep["copies"] - 1)
    new = np.asarray(mesh.vertices)[len(v):]
    assert np.max(np.abs(np.linalg.norm(new, axis=1) - 1)) < 1e-9
    assert euler(len(mesh.vertices), [list(x) for x in mesh.faces]) == 2
    # Optimised: the edge lengths move towards the rim's mean edge length.
    _, opt = atelier.extrude((v, f), strokes())
    target = opt["base_mean_edge"]
    assert abs(opt["after"]["mean"] - target) < abs(opt["before"]["mean"] - target)


def test_same_file_as_the_cli(scratch):
    v, f = cup()
    atelier.write_mesh(scratch / "cup.obj", v, f)
    (scratch / "strokes.json").write_text(json.dumps(strokes()))
    run_cli("--threads", 1, "extrude", "--mesh", scratch / "cup.obj", "--strokes", scratch / "strokes.json",
            "--out", scratch / "cli.obj", "--json", scratch / "cli.json")
    mesh, rep = atelier.extrude(atelier.read_mesh(scratch / "cup.obj"), scratch / "strokes.json", threads=2)
    atelier.write_mesh(scratch / "py.obj", mesh)
    assert (scratch / "py.obj").read_bytes() == (scratch / "cli.obj").read_bytes()
    theirs = json.loads((scratch / "cli.json").read_text())
    assert theirs["ok"] and theirs["copies"] == rep["copies"] and theirs["volume_change"] == rep["volume_change"]


def test_bad_strokes_raise_with_the_engines_message():
    v, f = cup()
    with pytest.raises(ValueError, match="does not start near the base curve"):
        atelier.extrude((v, f), strokes(start_y=0.5))
    bad = strokes()
    bad["strokes"][1]["points"][3][0] = float("nan")
    with pytest.raises(ValueError, match="non-finite|NaN"):
        atelier.extrude((v, f), bad)
    lone = strokes()
    del lone["strokes"][1]
    with pytest.raises(ValueError, match="run of 2 or 3 extrude strokes"):
        atelier.extrude((v, f), lone)


def test_optimised_edges_within_bounds_and_as_surface():
    v, f = cup()
    mesh, rep = atelier.extrude((v, f), strokes(), as_surface=True)
    assert rep["after"]["outside"] == 0 and rep["after"]["within"] == 1.0
    assert rep["max_deviation"] < 0.1 * rep["base_mean_edge"]
    assert rep["joints"] == 1
    # The cup's faces and the dome's in two surfaces.
    fs = np.asarray(mesh.face_surface)
    assert sorted(np.unique(fs).tolist()) == [0, 1]
    assert np.count_nonzero(fs == fs[0]) == len(f)


def test_mirror_across_a_plane_through_the_base_is_refused():
    """The cup's rim straddles x = 0: the mirrored pair is refused (the
    message names the side), a bad mirror argument raises too."""
    v, f = cup()
    with pytest.raises(ValueError, match="side"):
        atelier.extrude((v, f), strokes(), mirror="x")
    with pytest.raises(ValueError, match="mirror"):
        atelier.extrude((v, f), strokes(), mirror="w")


def test_a_recipe_replays_the_dome_on_a_moved_and_scaled_cup(scratch):
    """extrude's report["recipe"] grows the same dome on another cup of the
    same topology (replay_extrusion, `atelier extrude --replay`): on the cup
    it was drawn on, the drawn dome; on a cup turned, scaled by 1.7 and moved,
    the dome under the same similarity (the part follows its base curve)."""
    v, f = cup()
    drawn, rep = atelier.extrude((v, f), strokes(), optimise=False)
    recipe = rep["recipe"]
    assert recipe is not None
    again, rep2 = atelier.replay_extrusion((v, f), recipe, optimise=False)
    assert rep2["copies"] == rep["copies"] and "recipe" not in rep2
    assert np.abs(np.asarray(again.vertices) - np.asarray(drawn.vertices)).max() < 1e-12
    assert [list(x) for x in again.faces] == [list(x) for x in drawn.faces]

    c, s = np.cos(0.4), np.sin(0.4)
    rot = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    move = lambda p: 1.7 * np.asarray(p) @ rot.T + np.array([0.3, -2.0, 5.0])  # noqa: E731
    moved, _ = atelier.replay_extrusion((move(v), f), recipe, optimise=False)
    assert np.abs(np.asarray(moved.vertices) - move(drawn.vertices)).max() < 1e-9
    # The CLI's recipe file is the same recipe: the same mesh from the path.
    (scratch / "recipe.json").write_text(json.dumps(recipe))
    from_file, _ = atelier.replay_extrusion((move(v), f), scratch / "recipe.json", optimise=False)
    assert np.array_equal(np.asarray(from_file.vertices), np.asarray(moved.vertices))


def test_a_bad_recipe_is_refused_naming_what_is_wrong(scratch):
    v, f = cup()
    _, rep = atelier.extrude((v, f), strokes(), optimise=False)
    recipe = rep["recipe"]
    broken = json.loads(json.dumps(recipe))
    key = next(k for k, x in broken.items() if isinstance(x, list))
    del broken[key]
    with pytest.raises(ValueError, match=key):
        atelier.replay_extrusion((v, f), broken)
    # A mesh without the base nodes (a smaller cup) is refused.
    small_v, small_f = cup(8)
    with pytest.raises(ValueError):
        atelier.replay_extrusion((small_v, small_f), recipe)
    with pytest.raises(FileNotFoundError):
        atelier.replay_extrusion((v, f), scratch / "none.json")
    with pytest.raises(TypeError):
        atelier.replay_extrusion((v, f), 42)


def closed_box(lo, hi):
    """A closed, outward triangulated box."""
    v = np.array([[hi[0] if k & 1 else lo[0], hi[1] if k & 2 else lo[1], hi[2] if k & 4 else lo[2]]
                  for k in range(8)])
    f = [[0, 4, 6], [0, 6, 2], [1, 3, 7], [1, 7, 5], [0, 1, 5], [0, 5, 4],
         [2, 6, 7], [2, 7, 3], [0, 2, 3], [0, 3, 1], [4, 5, 7], [4, 7, 6]]
    return v, f


def test_a_body_keeps_the_dome_outside_and_the_cli_gives_the_same_file(scratch):
    """body= (``--body``): a box the dome's top enters. Without it nodes are
    inside the box; with it none is (checked here against the box itself),
    the report says what was pushed, and with the two passes around the push
    (body_smoothing, settle_rounds) the CLI's flags give the same file bytes."""
    v, f = cup()
    lo, hi = (-0.3, 0.6, -0.3), (0.3, 1.2, 0.3)

    def inside(points):
        p = np.asarray(points)
        return np.count_nonzero(np.all((p > np.array(lo)) & (p < np.array(hi)), axis=1))

    free, rep0 = atelier.extrude((v, f), strokes())
    assert inside(free.vertices) > 0 and "inside_after" not in rep0
    mesh, rep = atelier.extrude((v, f), strokes(), body=closed_box(lo, hi), clearance=0.01)
    assert rep["pushed"] > 0 and rep["inside_after"] == 0 and rep["min_body_distance"] > 0
    assert inside(mesh.vertices) == 0
    smooth, rep2 = atelier.extrude((v, f), strokes(), body=closed_box(lo, hi), clearance=0.01, body_smoothing=3,
                                   settle_rounds=2, threads=2)
    assert rep2["inside_after"] == 0 and inside(smooth.vertices) == 0
    assert not np.array_equal(np.asarray(smooth.vertices), np.asarray(mesh.vertices))  # the passes ran
    atelier.write_mesh(scratch / "cup.obj", v, f)
    atelier.write_mesh(scratch / "box.obj", *closed_box(lo, hi))
    (scratch / "strokes.json").write_text(json.dumps(strokes()))
    run_cli("--threads", 1, "extrude", "--mesh", scratch / "cup.obj", "--strokes", scratch / "strokes.json",
            "--out", scratch / "cli.obj", "--body", scratch / "box.obj", "--clearance", 0.01,
            "--body-smoothing", 3, "--settle-rounds", 2, "--json", scratch / "cli.json")
    atelier.write_mesh(scratch / "py.obj", smooth)
    assert (scratch / "py.obj").read_bytes() == (scratch / "cli.obj").read_bytes()
    theirs = json.loads((scratch / "cli.json").read_text())
    assert theirs["pushed"] == rep2["pushed"] and theirs["inside_after"] == 0
    # A replayed dome is kept outside the same way.
    again, rep3 = atelier.replay_extrusion((v, f), rep0["recipe"], body=closed_box(lo, hi), clearance=0.01)
    assert rep3["inside_after"] == 0 and inside(again.vertices) == 0
    with pytest.raises(ValueError, match="body"):
        atelier.extrude((v, f), strokes(), body=(np.zeros((3, 3)), [[0, 1, 1]]))
    with pytest.raises(ValueError, match="clearance"):
        atelier.extrude((v, f), strokes(), body=closed_box(lo, hi), clearance=float("nan"))
