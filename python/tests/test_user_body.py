"""A user's own reference body (issue 26): Body.read in centimetres and Z-up
gives the garments of the same body in metres and Y-up."""
import numpy as np
import pytest

import atelier
from conftest import demo_shorts


def write_obj(path, vertices, faces):
    with open(path, "w") as f:
        for v in vertices:
            f.write("v %.17g %.17g %.17g\n" % tuple(v))
        for face in faces:
            f.write("f " + " ".join(str(int(i) + 1) for i in face) + "\n")


def to_cm_z_up(p):
    """Metres, Y-up (X, Y, Z) as centimetres, Z-up (X, -Z, Y)."""
    p = np.asarray(p, dtype=np.float64)
    return np.stack([100 * p[:, 0], -100 * p[:, 2], 100 * p[:, 1]], axis=1)


def test_a_body_and_garment_in_centimetres_z_up_encode_as_in_metres_y_up(small, scratch):
    body, bodies = small["body"], small["bodies"]
    v, f = demo_shorts(body)
    # Garment files are read in float precision: on a grid of 2^-16 m a
    # coordinate and 100 times it are both floats. Body coordinates as
    # floats: 100 times them is exact. So both frames give the same bits.
    v = np.round(np.asarray(v, dtype=np.float64) * 65536) / 65536
    bv = np.asarray(body.vertices, dtype=np.float32).astype(np.float64)
    write_obj(scratch / "body_m.obj", bv, body.faces)
    write_obj(scratch / "body_cm.obj", to_cm_z_up(bv), body.faces)
    write_obj(scratch / "shorts_m.obj", v, f)
    write_obj(scratch / "shorts_cm.obj", to_cm_z_up(v), f)
    ref_m = atelier.Body.read(scratch / "body_m.obj")
    ref_cm = atelier.Body.read(scratch / "body_cm.obj", scale=0.01, up="z")
    assert np.array_equal(ref_cm.vertices, ref_m.vertices)
    g_m = atelier.encode_garment(atelier.GarmentFamily(ref_m), scratch / "shorts_m.obj")
    g_cm = atelier.encode_garment(atelier.GarmentFamily(ref_cm), scratch / "shorts_cm.obj", scale=0.01, up="z")
    assert g_cm.name == "shorts_cm"
    r_m = atelier.regenerate(g_m, bodies)
    r_cm = atelier.regenerate(g_cm, bodies)
    assert r_m.ok.all() and r_cm.ok.all()
    pm, pc = r_m.positions[0], r_cm.positions[0]
    assert not np.allclose(pm[0], g_m.vertices)  # the garment followed the body
    assert np.array_equal(pc, pm)


def test_an_open_body_and_a_bad_axis_are_refused(scratch):
    write_obj(scratch / "open.obj", [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], [[0, 2, 1], [0, 1, 3], [0, 3, 2]])
    with pytest.raises(ValueError, match="open.obj.*not closed"):
        atelier.Body.read(scratch / "open.obj")
    with pytest.raises(ValueError, match="up"):
        atelier.Body.read(scratch / "open.obj", up="x")
    with pytest.raises(FileNotFoundError):
        atelier.Body.read(scratch / "none.obj")


# The mannequin's open feature curves (docs/body-files.md); the others are loops.
OPEN_CURVES = {"shoulder_left", "shoulder_right", "centre_front", "centre_back", "side_left", "side_right"}


def write_curves(path, body, mapping, units=None, up=None):
    import json

    doc = {}
    if units:
        doc["units"] = units
    if up:
        doc["up"] = up
    doc["curves"] = [
        {"name": n, "closed": n not in OPEN_CURVES, "points": mapping(body.curve(n)).tolist()} for n in body.curves
    ]
    path.write_text(json.dumps(doc))


def test_feature_curves_from_a_file_make_profile_templates_apply(small, scratch):
    body = small["body"]
    v = np.asarray(body.vertices, dtype=np.float32).astype(np.float64)
    # Renumbered vertices: no longer the mannequin's topology, so the file
    # is the only source of the body's curves.
    perm = np.random.default_rng(3).permutation(len(v))
    inv = np.empty_like(perm)
    inv[perm] = np.arange(len(v))
    faces = [inv[np.asarray(face)] for face in body.faces]
    v2 = np.empty_like(v)
    v2[inv] = v
    write_obj(scratch / "body_m.obj", v2, faces)
    write_obj(scratch / "body_cm.obj", to_cm_z_up(v2), faces)
    write_curves(scratch / "curves_m.json", body, lambda p: np.asarray(p))
    write_curves(scratch / "curves_cm.json", body, to_cm_z_up, units="cm", up="z")

    plain = atelier.Body.read(scratch / "body_m.obj")
    assert plain.curves == []
    with pytest.raises(ValueError):
        atelier.project_templates(plain)

    mine = atelier.Body.read(scratch / "body_m.obj", features=scratch / "curves_m.json")
    mine_cm = atelier.Body.read(scratch / "body_cm.obj", scale=0.01, up="z", features=scratch / "curves_cm.json")
    assert mine.curves == body.curves and mine_cm.curves == body.curves
    # Every curve crossing of the engine's own is found again from the
    # file's polylines (named "<closed>_x_<open>": the mannequin names the
    # shoulder-armhole crossings the other way round).
    swap = lambda n: "_x_".join(reversed(n.split("_x_")))  # noqa: E731
    assert all(p in mine.points or swap(p) in mine.points for p in body.points)
    for n in body.curves:
        snapped, own = mine.curve(n), body.curve(n)
        assert snapped.shape == own.shape, n
        assert np.abs(snapped - own).max() < 1e-6, n  # points on the skin stay where they were
        assert np.abs(mine_cm.curve(n) - snapped).max() < 1e-9, n  # units and axes of the file
    names = [t.name for t in atelier.project_templates(mine)]
    assert names == [t.name for t in atelier.project_templates(body)]


def test_a_feature_file_with_a_point_off_the_body_is_refused_naming_it(small, scratch):
    import json

    body = small["body"]
    write_obj(scratch / "body.obj", np.asarray(body.vertices), body.faces)
    far = body.curve("waist") * 1.5
    (scratch / "bad.json").write_text(
        json.dumps({"curves": [{"name": "waist", "closed": True, "points": far.tolist()}]}, indent=1)
    )
    with pytest.raises(ValueError, match=r"bad\.json.*waist"):
        atelier.Body.read(scratch / "body.obj", features=scratch / "bad.json")
    with pytest.raises(FileNotFoundError):
        atelier.Body.read(scratch / "body.obj", features=scratch / "none.json")
