"""Files and arrays: round trips through every mesh format, PNG, errors with
the engine's message, atomic writes, zero-copy views."""
import errno
import gc

import numpy as np
import pytest

import atelier


def grid(nx=5, ny=4, dtype=np.float64):
    """A wavy quad grid: exact doubles that need 17 digits."""
    x, y = np.meshgrid(np.linspace(0, 1, nx), np.linspace(0, 1, ny))
    z = np.sin(3.1 * x) * np.cos(2.3 * y) / 7.0
    v = np.stack([x.ravel(), y.ravel(), z.ravel()], axis=1).astype(dtype)
    f = []
    for j in range(ny - 1):
        for i in range(nx - 1):
            a = j * nx + i
            f.append([a, a + 1, a + nx + 1, a + nx])
    return v, np.array(f, dtype=np.int64)


@pytest.mark.parametrize("ext", [".obj", ".ply", ".off", ".atm"])
def test_write_read_round_trip_is_bit_exact(scratch, ext):
    v, f = grid()
    path = scratch / ("grid" + ext)
    atelier.write_mesh(path, v, f)
    v2, f2 = atelier.read_mesh(path)
    assert v2.dtype == np.float64 and f2.dtype == np.uint32
    assert v2.shape == v.shape and f2.shape == f.shape
    assert np.array_equal(v2.view(np.uint64), v.view(np.uint64))  # bit for bit
    assert np.array_equal(f2, f)
    # And again from the Mesh read back: the same bytes.
    path2 = scratch / ("again" + ext)
    atelier.write_mesh(path2, atelier.read_mesh(path))
    assert path2.read_bytes() == path.read_bytes()


def test_ascii_ply_and_mixed_polygons_round_trip(scratch):
    v = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0.5, 0]], dtype=np.float32)
    faces = [[0, 1, 2, 3], [1, 4, 2]]  # a quad and a triangle
    path = scratch / "mixed.ply"
    atelier.write_mesh(path, v, faces, binary=False)
    mesh = atelier.read_mesh(path)
    assert np.array_equal(mesh.vertices, v.astype(np.float64))
    assert [list(x) for x in mesh.faces] == faces  # a list of arrays: polygons of two sizes
    assert list(mesh.face_offsets) == [0, 4, 7]
    assert list(mesh.face_indices) == [0, 1, 2, 3, 1, 4, 2]
    # Fan triangles (c0, c[j+1], c[j+2]).
    assert mesh.triangles.tolist() == [[0, 1, 2], [0, 2, 3], [1, 4, 2]]


def test_obj_groups_become_surfaces(scratch):
    path = scratch / "groups.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\ng front\nf 1 2 3\ng back\nf 1 3 4\n")
    mesh = atelier.read_mesh(path)
    assert mesh.surfaces == ["front", "back"]
    assert mesh.face_surface.tolist() == [0, 1]
    # A vertex of two surfaces is one node per surface (io/obj.h).
    assert mesh.vertex_count == 6 and mesh.face_count == 2


def test_png_round_trip(scratch):
    rng = np.random.default_rng(3)
    img = rng.integers(0, 256, size=(7, 11, 3), dtype=np.uint8)
    atelier.write_png(scratch / "x.png", img)
    back = atelier.read_png(scratch / "x.png")
    assert back.dtype == np.uint8 and np.array_equal(back, img)


def test_missing_file_is_file_not_found_with_the_path(scratch):
    path = scratch / "nope.obj"
    with pytest.raises(FileNotFoundError) as e:
        atelier.read_mesh(path)
    assert e.value.errno == errno.ENOENT and e.value.filename == str(path)
    assert isinstance(e.value, OSError)
    with pytest.raises(FileNotFoundError):
        atelier.read_png(scratch / "nope.png")


def test_malformed_files_raise_value_error_naming_file_and_line(scratch):
    path = scratch / "bad.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n")
    with pytest.raises(ValueError, match=r"bad\.obj.*4"):
        atelier.read_mesh(path)
    bad_off = scratch / "bad.off"
    bad_off.write_text("OFF\n3 1 0\n0 0 0\n1 0 zero\n0 1 0\n3 0 1 2\n")
    with pytest.raises(ValueError, match=r"bad\.off.*line 4"):
        atelier.read_mesh(bad_off)
    truncated = scratch / "cut.atm"
    v, f = grid()
    atelier.write_mesh(truncated, v, f)
    truncated.write_bytes(truncated.read_bytes()[:100])
    with pytest.raises(ValueError, match=r"cut\.atm"):
        atelier.read_mesh(truncated)
    with pytest.raises(ValueError, match="unknown mesh format"):
        atelier.read_mesh(scratch / "x.stl")


def test_a_failed_write_leaves_no_file(scratch):
    # Three faces on one edge: the engine's model refuses it (non-manifold).
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1]], dtype=float)
    f = [[0, 1, 2], [1, 0, 3], [0, 1, 4]]
    path = scratch / "fan.obj"
    with pytest.raises(ValueError, match="edge"):
        atelier.write_mesh(path, v, f)
    assert list(scratch.iterdir()) == []


def test_views_are_zero_copy_and_keep_their_owner_alive():
    v, f = grid()
    mesh = atelier.Mesh(v, f)
    a, b = mesh.vertices, mesh.vertices
    assert np.shares_memory(a, b)  # two views of one engine column
    assert not np.shares_memory(a, v)  # the constructor copied the caller's array once
    assert not a.flags.writeable
    with pytest.raises(ValueError):
        a[0, 0] = 1.0
    faces = mesh.faces
    assert np.shares_memory(faces, mesh.face_indices)
    del mesh
    gc.collect()
    assert np.array_equal(a, v) and np.array_equal(faces, f)  # the views kept the mesh alive


def test_mesh_validate_names_the_problem():
    v, f = grid()
    atelier.Mesh(v, f).validate()
    flipped = f.copy()
    flipped[0] = flipped[0][::-1]  # one face against its neighbours
    with pytest.raises(ValueError):
        atelier.Mesh(v, flipped).validate()
