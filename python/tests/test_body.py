"""Bodies: mannequin parameters in, positions out; measurements; a user's
own body arrays; MakeHuman bodies from the shared data."""
import numpy as np
import pytest

import atelier
from conftest import MAKEHUMAN


def test_sampled_parameters_are_the_cli_draws():
    rows = atelier.sample_mannequins(5, seed=7)
    assert rows.shape == (5,) and rows.dtype.names == tuple(atelier.mannequin_fields())
    for i in range(5):
        one = atelier.sample_mannequin(7, i)  # drawn on its own (what `--seed 7` gives body i)
        assert [one[k] for k in rows.dtype.names] == [rows[i][k] for k in rows.dtype.names]
    assert not np.array_equal(atelier.sample_mannequins(5, seed=8), rows)


def test_positions_follow_the_parameters(small):
    mannequin, params = small["mannequin"], small["params"][:4]
    p64 = mannequin.positions(params)
    p32 = mannequin.positions(params, dtype=np.float32, threads=1)
    assert p64.shape == (4, mannequin.node_count, 3) and p64.dtype == np.float64
    assert p32.dtype == np.float32 and np.array_equal(p32, p64.astype(np.float32))
    # A list of dicts and a structured array with a subset of fields (the
    # rest take the defaults) give the same bodies.
    as_dicts = [{k: float(r[k]) for k in params.dtype.names} for r in params]
    assert np.array_equal(mannequin.positions(as_dicts), p64)
    one = mannequin.positions({"height": 1.62})
    assert one.shape == (mannequin.node_count, 3)
    assert np.array_equal(one, mannequin.positions([{"height": 1.62}])[0])


def test_mannequin_girths_match_the_request(small):
    # The mannequin fits each measured ring to the requested tape girth
    # exactly (systems/body/mannequin.h): an independent check of the
    # parameters going in and the positions coming out.
    mannequin, body = small["mannequin"], small["body"]
    params = small["params"][:3]
    bodies = mannequin.positions(params)
    table = body.measure_many(bodies, threads=2)
    assert table.shape == (3,) and "waist_girth" in table.dtype.names
    for b in range(3):
        for name in ("waist", "hip", "bust", "neck_base" if "neck_base_girth" in table.dtype.names else "waist"):
            requested = params[b][name + "_girth"] if name + "_girth" in params.dtype.names else None
            if requested is not None:
                assert abs(table[b][name + "_girth"] - requested) < 1e-6
        one = body.measure(bodies[b])
        assert list(one) == list(table.dtype.names)
        assert [one[k] for k in one] == [table[b][k] for k in one]


def test_reference_body_features(small):
    body = small["body"]
    assert {"waist", "hip", "centre_front"} <= set(body.curves)
    assert body.points
    waist = body.curve("waist")
    assert waist.ndim == 2 and waist.shape[1] == 3
    # The same curve on a moved body follows the nodes.
    moved = body.vertices + np.array([0.0, 0.5, 0.0])
    assert np.allclose(body.curve("waist", moved), waist + [0.0, 0.5, 0.0])
    other = body.with_positions(moved)
    assert other.curves == body.curves and np.array_equal(other.vertices, moved)
    with pytest.raises(ValueError, match=r"no feature curve 'nope'|no feature curve nope"):
        body.curve("nope")
    assert body.triangles.shape[1] == 3 and body.triangles.max() < body.node_count
    assert np.shares_memory(body.vertices, body.vertices)


def test_a_users_own_body_from_arrays(small):
    ref = small["body"]
    mine = atelier.Body.from_arrays(ref.vertices.astype(np.float32), ref.faces)
    assert mine.node_count == ref.node_count and mine.curves == []
    assert np.array_equal(mine.mesh.face_indices, ref.mesh.face_indices)
    assert np.array_equal(mine.mesh.face_offsets, ref.mesh.face_offsets)
    # Garments encode on it (a closed skin); it has no features to measure.
    family = atelier.GarmentFamily(mine)
    assert family.node_count == ref.node_count
    open_skin = atelier.Body.from_arrays(ref.vertices, ref.faces[:-10])
    with pytest.raises(ValueError, match="reference body"):
        atelier.GarmentFamily(open_skin)


@pytest.fixture(scope="module")
def makehuman():
    if not (MAKEHUMAN / "base.obj").exists():
        pytest.skip(f"no MakeHuman data at {MAKEHUMAN}")
    return atelier.MakeHuman(MAKEHUMAN)


def test_makehuman_bodies(makehuman):
    ref = makehuman.reference()
    assert ref.node_count == makehuman.node_count
    rows = atelier.MakeHuman.sample(3, seed=4)
    assert rows.dtype.names[:3] == ("gender", "age", "muscle")
    bodies = makehuman.positions(rows, dtype=np.float32, threads=2)
    assert bodies.shape == (3, makehuman.node_count, 3)
    assert np.array_equal(bodies, makehuman.positions(rows, threads=1).astype(np.float32))
    # The default parameters give the reference body (metres).
    default = makehuman.positions({})
    assert np.allclose(default, ref.vertices, atol=1e-6)
    # A measure modifier changes the waist and little else.
    slim = makehuman.positions({"measures": {"measure-waist-circ": -1.0}})
    w0 = ref.measure(default)["waist_girth"]
    w1 = ref.measure(slim)["waist_girth"]
    assert w1 < w0
    with pytest.raises(ValueError):
        makehuman.positions({"measures": {"no-such-modifier": 0.5}})


def test_makehuman_missing_folder(scratch):
    with pytest.raises(FileNotFoundError):
        atelier.MakeHuman(scratch / "nowhere")


def test_makehuman_adults_have_survey_statures(makehuman):
    # Issue 26: regen's adults, with their statures (soles on y = 0).
    rows, stature = makehuman.adults(200, seed=5)
    assert rows.shape == (200,) and stature.shape == (200,)
    assert stature.max() <= 2.10 and stature.min() >= 1.40
    bodies = makehuman.positions(rows[:4], threads=2)
    for b in range(4):
        y = bodies[b][:, 1]
        assert abs(y.min()) < 1e-9
        assert abs((y.max() - y.min()) - stature[b]) < 1e-5
    female = stature[rows["gender"] < 0.5]
    male = stature[rows["gender"] >= 0.5]
    assert abs(np.median(female) - 1.615) < 0.02 and abs(np.median(male) - 1.755) < 0.02

