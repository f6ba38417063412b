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
