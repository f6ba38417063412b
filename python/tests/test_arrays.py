"""Bad arrays: each a clear ValueError naming the argument and the element,
never a crash; wrong arguments of the long calls likewise."""
import numpy as np
import pytest

import atelier

TRI_V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=np.float64)
TRI_F = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]], dtype=np.int32)  # a closed tetrahedron


@pytest.mark.parametrize(
    "vertices, pattern",
    [
        (np.zeros((4, 2)), r"expected an \(n, 3\) array, got shape \(4, 2\)"),
        (np.zeros((4, 3, 1)), r"expected an \(n, 3\) array, got shape \(4, 3, 1\)"),
        (np.zeros(12), r"got shape \(12,\)"),
        (np.zeros((4, 3), dtype=np.int64), r"dtype int64; expected float32 or float64"),
        (np.zeros((4, 3), dtype=np.complex128), r"dtype complex128"),
        (np.zeros((4, 3), dtype=np.float16), r"dtype float16"),
        (np.array([["a", "b", "c"]] * 4), r"dtype <U1"),
        ([[0, 0, 0], [1, 0], [0, 1, 0], [0, 0, 1]], r"not an array"),
    ],
)
def test_bad_vertex_arrays(vertices, pattern):
    with pytest.raises(ValueError, match=pattern):
        atelier.Mesh(vertices, TRI_F)


@pytest.mark.parametrize("value", [np.nan, np.inf, -np.inf])
def test_non_finite_vertices_name_the_vertex(value):
    v = TRI_V.copy()
    v[2, 1] = value
    with pytest.raises(ValueError, match=r"mesh vertices: vertex 2 is not finite"):
        atelier.Mesh(v, TRI_F)
    with pytest.raises(ValueError, match=r"vertex 2 is not finite"):
        atelier.write_mesh("/nonexistent/never.obj", v, TRI_F)


@pytest.mark.parametrize(
    "faces, pattern",
    [
        (np.array([[0, 1, 4]]), r"face 0 uses vertex 4, the mesh has 4 vertices"),
        (np.array([[0, 1, 2], [0, -1, 2]]), r"face 1 uses vertex -1"),
        (np.array([[0, 1, 2**40]], dtype=np.int64), r"face 0 uses vertex 1099511627776"),
        (np.array([[0, 1, 2**63 + 5]], dtype=np.uint64), r"face 0 uses vertex -1"),
        (np.array([[0, 1]]), r"shape \(1, 2\)"),
        (np.array([0, 1, 2]), r"shape \(3,\)"),
        (np.array([[0.0, 1.0, 2.0]]), r"dtype float64"),
        (np.array([[True, False, True]]), r"dtype bool"),
        ([[0, 1, 2], [0, 1]], r"face 1 has 2 corners \(at least 3\)"),
        ([[0, 1, 2], [0, 1, 9, 3]], r"face 1 uses vertex 9"),
        ([[0, 1, 2], ["a", "b", "c"]], r"dtype <U"),
        ([[0, 1, 2], [0, 1, "x", 3]], r"face 1 is not a 1-D list of integers"),
        ("012", r"str"),
    ],
)
def test_bad_face_arrays(faces, pattern):
    with pytest.raises(ValueError, match=pattern):
        atelier.Mesh(TRI_V, faces)


def test_any_integer_dtype_and_strides_are_accepted():
    for dt in (np.int8, np.uint16, np.int32, np.uint32, np.int64, np.uint64):
        m = atelier.Mesh(TRI_V, TRI_F.astype(dt))
        assert np.array_equal(m.faces, TRI_F)
    # Non-contiguous inputs are read in place (strides), not refused.
    wide = np.zeros((4, 6))
    wide[:, ::2] = TRI_V
    m = atelier.Mesh(wide[:, ::2], np.asfortranarray(TRI_F))
    assert np.array_equal(m.vertices, TRI_V) and np.array_equal(m.faces, TRI_F)


def test_bad_body_batches(small):
    shorts, bodies = small["shorts"], small["bodies"]
    n = bodies.shape[1]
    with pytest.raises(ValueError, match=r"expected a \(B, n, 3\) array of B bodies, got shape"):
        atelier.regenerate(shorts, bodies[0])
    with pytest.raises(ValueError, match=rf"{n - 1} vertices per body; the body family has {n}"):
        atelier.regenerate(shorts, bodies[:, 1:, :])
    with pytest.raises(ValueError, match=r"dtype int32"):
        atelier.regenerate(shorts, bodies.astype(np.int32))
    bad = bodies[:3].copy()
    bad[2, 17, 0] = np.nan
    with pytest.raises(ValueError, match=r"bodies: body 2, vertex 17 is not finite"):
        atelier.regenerate(shorts, bad)
    with pytest.raises(ValueError, match=r"threads must be 0 \(all cores\) or more"):
        atelier.regenerate(shorts, bodies[:1], threads=-1)
    with pytest.raises(ValueError, match=r"dtype must be float32 or float64"):
        atelier.regenerate(shorts, bodies[:1], dtype=np.int16)
    with pytest.raises(ValueError, match=r"chunk"):
        atelier.regenerate(shorts, bodies[:1], chunk=0)
    with pytest.raises(TypeError):
        atelier.regenerate("shorts", bodies[:1])


def test_bad_parameters(small):
    mannequin = small["mannequin"]
    with pytest.raises(ValueError, match=r"unknown field 'heigth'"):
        mannequin.positions({"heigth": 1.8})
    with pytest.raises(ValueError, match=r"params\[0\]\['height'\]: not finite"):
        mannequin.positions({"height": float("nan")})
    with pytest.raises(ValueError, match=r"params\[0\]: .*"):  # validate_params: out of range
        mannequin.positions({"height": 9.0})
    with pytest.raises(ValueError, match=r"structured array"):
        mannequin.positions(np.zeros((3, 13)))
    rows = atelier.sample_mannequins(3, seed=2)
    with pytest.raises(ValueError, match=r"unknown field 'wrong'"):
        mannequin.positions(rows.astype([("wrong", "f8")] + [(n, "f8") for n in rows.dtype.names[1:]]))


def test_bad_garment_inputs(small):
    family = small["family"]
    with pytest.raises(ValueError, match=r"garment faces: face 0 uses vertex 3"):
        atelier.encode_garment(family, TRI_V[:3], [[0, 1, 3]])
    with pytest.raises(ValueError, match=r"edges: edge 0 uses a vertex out of range"):
        atelier.encode_garment(family, TRI_V, TRI_F, edges=[[0, 7]])
    with pytest.raises(ValueError, match=r"body: 4 vertices; the body has"):
        atelier.Regenerator(small["shorts"]).run_one(TRI_V)
