"""Net Booleans, trimming and rounding off (atelier.boolean, trim, round_off;
systems/net, seed 004): volumes against the analytic boxes, the same bits
as `atelier boolean` for the same files, a trimmed plane against the
polygon's area, and a ValueError with the engine's message for bad input."""
import json
import subprocess

import numpy as np
import pytest

import atelier
from conftest import cli, run_cli


def box(lo, hi):
    """An axis-aligned box as 6 outward, counter-clockwise quads."""
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    v = np.array([[x0, y0, z0], [x1, y0, z0], [x1, y1, z0], [x0, y1, z0],
                  [x0, y0, z1], [x1, y0, z1], [x1, y1, z1], [x0, y1, z1]], dtype=np.float64)
    f = np.array([[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [2, 3, 7, 6], [1, 2, 6, 5], [0, 4, 7, 3]])
    return v, f


def polygons(faces):
    return [list(p) for p in faces] if isinstance(faces, list) else faces.tolist()


def volume(v, faces):
    """Divergence theorem over fan triangles (independent of the engine)."""
    total = 0.0
    for p in polygons(faces):
        for j in range(1, len(p) - 1):
            total += np.dot(v[p[0]], np.cross(v[p[j]], v[p[j + 1]])) / 6.0
    return total


def edge_uses(faces):
    uses = {}
    for p in polygons(faces):
        for a, b in zip(p, p[1:] + p[:1]):
            uses[(min(a, b), max(a, b))] = uses.get((min(a, b), max(a, b)), 0) + 1
    return uses


A = box((0, 0, 0), (1, 1, 1))
B = box((0.45, 0.3, 0.2), (1.45, 1.3, 1.2))
OVERLAP = 0.55 * 0.7 * 0.8


@pytest.mark.parametrize("op,expected", [("union", 2 - OVERLAP), ("intersection", OVERLAP),
                                         ("difference", 1 - OVERLAP), ("b-a", 1 - OVERLAP)])
def test_overlapping_boxes_have_the_analytic_volume(op, expected):
    v, f, rep = atelier.boolean(A, B, op=op)
    assert abs(volume(v, f) - expected) < 1e-12
    assert abs(rep["volume"]["result"] - expected) < 1e-12
    assert rep["volume"]["a"] == pytest.approx(1.0) and rep["volume"]["b"] == pytest.approx(1.0)
    assert rep["intersection_polygons"] == 1
    assert not v.flags.writeable and v.base is not None  # a view onto the engine's result
    # Watertight: every edge shared by exactly two faces.
    assert set(edge_uses(f).values()) == {2}
    # The seam lies on both boxes' surfaces.
    assert rep["seam"].dtype == np.uint32 and len(rep["seam"]) > 0


def test_union_of_disjoint_boxes_and_same_bits_as_the_cli(scratch):
    far = box((3, 0, 0), (4, 1, 1))
    v, f, rep = atelier.boolean(A, far)
    assert abs(volume(v, f) - 2.0) < 1e-12 and rep["intersection_polygons"] == 0
    # The CLI on the same files writes the same vertices and faces.
    atelier.write_mesh(scratch / "a.obj", *A)
    atelier.write_mesh(scratch / "b.obj", *B)
    run_cli("boolean", "--op", "union", scratch / "a.obj", scratch / "b.obj", "--out", scratch / "out.obj")
    ours_v, ours_f, _ = atelier.boolean(atelier.read_mesh(scratch / "a.obj"), atelier.read_mesh(scratch / "b.obj"),
                                        op="union", threads=1)
    theirs_v, theirs_f = atelier.read_mesh(scratch / "out.obj")
    assert ours_v.tobytes() == theirs_v.tobytes()
    assert polygons(ours_f) == polygons(theirs_f)


def test_exact_refinement_same_volume_every_cut_triangle_exact_as_the_cli(scratch):
    """exact_refinement (``--exact-refinement``): every cut triangle goes to
    the exact triangulation (the default's certified fast path takes them
    all on these boxes), the same volume to the last bits the analytic one
    allows, and the CLI reports the same counts for the same files."""
    v, f, fast = atelier.boolean(A, B, op="union")
    ev, ef, exact = atelier.boolean(A, B, op="union", exact_refinement=True)
    assert fast["cut_triangles"] > 0
    assert fast["refined_exact"] < fast["cut_triangles"]
    assert exact["refined_exact"] == exact["cut_triangles"] == fast["cut_triangles"]
    assert abs(volume(ev, ef) - (2 - OVERLAP)) < 1e-12 and set(edge_uses(ef).values()) == {2}
    atelier.write_mesh(scratch / "a.obj", *A)
    atelier.write_mesh(scratch / "b.obj", *B)
    run_cli("--threads", 1, "boolean", scratch / "a.obj", scratch / "b.obj", "--out", scratch / "out.obj",
            "--exact-refinement", "--json", scratch / "r.json")
    theirs = json.loads((scratch / "r.json").read_text())
    assert theirs["refined_exact"] == theirs["cut_triangles"] == exact["cut_triangles"]
    mine_v, mine_f, _ = atelier.boolean(atelier.read_mesh(scratch / "a.obj"), atelier.read_mesh(scratch / "b.obj"),
                                        exact_refinement=True, threads=1)
    tv, tf = atelier.read_mesh(scratch / "out.obj")
    assert mine_v.tobytes() == tv.tobytes() and polygons(mine_f) == polygons(tf)


def test_check_result_keeps_a_result_that_does_not_fold_as_the_cli(scratch):
    """check_result (on by default since fold16; ``--no-check-result`` and
    check_result=False switch it off): a result that does not fold once
    rounded comes back with the same bytes with and without the check, here
    and from the CLI (folded results repaired or refused: the C++ campaign's
    NetDegeneratePairs.CheckResultNeverReturnsWhatRoundingFolds)."""
    for op in ("union", "intersection", "difference"):
        v, f, _ = atelier.boolean(A, B, op=op)
        ov, of, _ = atelier.boolean(A, B, op=op, check_result=False)
        assert v.tobytes() == ov.tobytes() and polygons(f) == polygons(of)
    atelier.write_mesh(scratch / "a.obj", *A)
    atelier.write_mesh(scratch / "b.obj", *B)
    ma, mb = atelier.read_mesh(scratch / "a.obj"), atelier.read_mesh(scratch / "b.obj")
    for flag, check in (("--check-result", True), ("--no-check-result", False), (None, True)):
        args = ["--threads", 1, "boolean", scratch / "a.obj", scratch / "b.obj", "--out", scratch / "out.obj"]
        run_cli(*(args + ([flag] if flag else [])))
        mine_v, mine_f, _ = atelier.boolean(ma, mb, check_result=check, threads=1)
        tv, tf = atelier.read_mesh(scratch / "out.obj")
        assert mine_v.tobytes() == tv.tobytes() and polygons(mine_f) == polygons(tf)
    # Both flags at once: a clear error, not a silent pick.
    r = subprocess.run([cli(), "boolean", str(scratch / "a.obj"), str(scratch / "b.obj"), "--out",
                        str(scratch / "out.obj"), "--check-result", "--no-check-result"],
                       capture_output=True, text=True)
    assert r.returncode != 0 and "contradict" in (r.stdout + r.stderr)


def plane_and_ellipse(n=12):
    xs = np.linspace(-1, 1, n + 1)
    v = np.array([[x, y, 0.0] for y in xs for x in xs])
    f = np.array([[j * (n + 1) + i, j * (n + 1) + i + 1, (j + 1) * (n + 1) + i + 1, (j + 1) * (n + 1) + i]
                  for j in range(n) for i in range(n)])
    t = np.linspace(0, 2 * np.pi, 40, endpoint=False) + 0.013
    curve = np.stack([0.5 * np.cos(t), 0.47 * np.sin(t), np.zeros_like(t)], axis=1)
    return v, f, curve


def test_trimmed_plane_loses_the_curve_polygon_area():
    v, f, curve = plane_and_ellipse()
    polygon_area = 0.5 * abs(np.dot(curve[:, 0], np.roll(curve[:, 1], -1)) - np.dot(curve[:, 1], np.roll(curve[:, 0], -1)))
    tv, tf, rep = atelier.trim((v, f), curve)
    assert rep["area"]["before"] == pytest.approx(4.0, abs=1e-12)
    assert rep["area"]["after"] == pytest.approx(4.0 - polygon_area, abs=1e-9)
    kept = atelier.trim((v, f), curve, keep_enclosed=True)[2]["area"]["after"]
    assert kept == pytest.approx(polygon_area, abs=1e-9)


def test_round_off_lowers_the_energy_of_a_union_seam():
    v, f, rep = atelier.boolean(A, B)
    rv, rf, r = atelier.round_off((v, f), rep["seam"], rings=1)
    assert r["moved"] and r["energy"]["after"] < r["energy"]["before"]
    assert r["free_vertices"] > 0 and rv.shape == v.shape
    assert np.abs(rv - v).max() > 1e-3  # the seam's neighbourhood moved
    assert polygons(rf) == polygons(f)  # only positions move


def test_trim_and_round_off_same_bits_as_the_cli(scratch):
    v, f, curve = plane_and_ellipse()
    atelier.write_mesh(scratch / "plane.obj", v, f)
    (scratch / "curve.txt").write_text("".join(" ".join(repr(float(x)) for x in p) + "\n" for p in curve))
    run_cli("trim", "--mesh", scratch / "plane.obj", "--curve", scratch / "curve.txt", "--out", scratch / "t.obj")
    tv, tf, _ = atelier.trim(atelier.read_mesh(scratch / "plane.obj"), curve)
    theirs_v, theirs_f = atelier.read_mesh(scratch / "t.obj")
    assert tv.tobytes() == theirs_v.tobytes() and polygons(tf) == polygons(theirs_f)
    # The union's seam as `boolean --seam-out` writes it, then `round` on the union's file.
    atelier.write_mesh(scratch / "a.obj", *A)
    atelier.write_mesh(scratch / "b.obj", *B)
    run_cli("boolean", scratch / "a.obj", scratch / "b.obj", "--out", scratch / "u.obj", "--seam-out",
            scratch / "seam.txt")
    _, _, rep = atelier.boolean(atelier.read_mesh(scratch / "a.obj"), atelier.read_mesh(scratch / "b.obj"))
    seam = [int(w) for line in (scratch / "seam.txt").read_text().splitlines() if not line.startswith("#")
            for w in line.split()]
    assert seam == rep["seam"].tolist()
    run_cli("round", "--mesh", scratch / "u.obj", "--seam", scratch / "seam.txt", "--out", scratch / "r.obj")
    rv, rf, _ = atelier.round_off(atelier.read_mesh(scratch / "u.obj"), rep["seam"])
    theirs_v, theirs_f = atelier.read_mesh(scratch / "r.obj")
    assert rv.tobytes() == theirs_v.tobytes() and polygons(rf) == polygons(theirs_f)


def test_bad_input_is_a_value_error_with_the_engines_message():
    v, f = A
    bad = v.copy()
    bad[2, 1] = np.nan
    with pytest.raises(ValueError, match="vertex 2 is not finite"):
        atelier.boolean((bad, f), B)
    with pytest.raises(ValueError, match="uses vertex 8"):
        atelier.boolean(A, (B[0], np.where(B[1] == 7, 8, B[1])))
    # An inward box: the engine's message, naming the argument.
    with pytest.raises(ValueError, match=r"b: net B .*oriented inwards"):
        atelier.boolean(A, (B[0], B[1][:, ::-1]))
    with pytest.raises(ValueError, match="op"):
        atelier.boolean(A, B, op="xor")
    with pytest.raises(ValueError, match="seam"):
        atelier.round_off(A, [0, 99])


def test_prepared_nets_give_the_bits_of_the_meshes_and_a_chain_of_one_call_steps():
    """PreparedNet: the Boolean on prepared nets is the one on the meshes
    (same bytes), a chain A - B - C on prepared results is the chain of
    one-call steps, and a net prepared without the self-test is refused by a
    Boolean that asks for it."""
    pa, pb = atelier.PreparedNet(A), atelier.PreparedNet(B)
    # A box's six planar convex quads split as fans, two triangles each
    # (issue 24, fold15; around a centroid it was four).
    assert pa.volume == pytest.approx(1.0, abs=1e-12) and pa.self_checked and pa.triangles == 12
    for op in ("union", "intersection", "difference", "b-a"):
        v, f, rep = atelier.boolean(A, B, op=op)
        pv, pf, prep = atelier.boolean(pa, pb, op=op)
        assert pv.tobytes() == v.tobytes() and polygons(pf) == polygons(f)
        assert prep["volume"] == rep["volume"] and prep["seam"].tolist() == rep["seam"].tolist()
        mv, mf, _ = atelier.boolean(pa, B, op=op)  # one prepared, one mesh
        assert mv.tobytes() == v.tobytes()
    C = box((-0.5, -0.5, -0.5), (0.25, 0.25, 1.5))  # bites A apart from B
    v1, f1, _ = atelier.boolean(A, B, op="difference")
    v2, f2, one = atelier.boolean((v1, f1), C, op="difference")
    _, _, r1 = atelier.boolean(pa, pb, op="difference", prepare_result=True)
    assert isinstance(r1["prepared"], atelier.PreparedNet) and r1["prepared"].self_checked
    assert r1["prepared"].volume == r1["volume"]["result"]
    cv, cf, r2 = atelier.boolean(r1["prepared"], atelier.PreparedNet(C), op="difference")
    assert cv.tobytes() == v2.tobytes() and polygons(cf) == polygons(f2)
    assert r2["volume"]["result"] == pytest.approx(1 - OVERLAP - 0.0625, abs=1e-12)
    # An empty result cannot be an operand: the reason, not an exception.
    _, f0, r0 = atelier.boolean(A, box((3, 3, 3), (4, 4, 4)), op="intersection", prepare_result=True)
    assert len(polygons(f0)) == 0 and "no faces" in r0["prepared_error"]
    unchecked = atelier.PreparedNet(B, self_check=False)
    assert not unchecked.self_checked
    with pytest.raises(ValueError, match="prepared without the self-intersection test"):
        atelier.boolean(pa, unchecked)
    assert atelier.boolean(pa, unchecked, self_check=False)[0].tobytes() == atelier.boolean(A, B)[0].tobytes()
