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


def tube(r=0.1, h=0.4, nu=24, nv=4):
    """A closed cylinder tube of quads about +y (a sleeve), faces outside."""
    a = 2 * np.pi * np.arange(nu) / nu
    v = np.array([[r * np.sin(t), h * j / nv, r * np.cos(t)] for j in range(nv + 1) for t in a])
    f = np.array([[j * nu + i, j * nu + (i + 1) % nu, (j + 1) * nu + (i + 1) % nu, (j + 1) * nu + i]
                  for j in range(nv) for i in range(nu)])
    return v, f


def test_made_to_measure_pattern_of_a_tube(tmp_path):
    # A tube needs a seam: the automatic one (a generator) opens it into a
    # rectangle as wide as the tube's girth (nu chords) at every named line.
    r, h, nu = 0.1, 0.4, 24
    out = tmp_path / "sleeve"
    rep = atelier.made_to_measure_pattern(tube(r, h, nu), str(out), lines=[("elbow", 0.5), ("cuff", 0.1)])
    assert rep["seams_opened"] == 1 and rep["flipped"] == 0 and rep["failed_seams"] == 0
    (piece,) = rep["pieces"]
    girth = 1000 * nu * 2 * r * np.sin(np.pi / nu)
    assert piece["height_mm"] == pytest.approx(1000 * h, abs=1e-6)
    assert piece["widths_mm"]["elbow"] == pytest.approx(girth, abs=1e-6)
    assert piece["widths_mm"]["cuff"] == pytest.approx(girth, abs=1e-6)
    (seam,) = rep["seams"]
    assert [a for a, _ in seam["lengths_mm"]] == pytest.approx([1000 * h, 1000 * h], abs=1e-6)
    names = sorted(p.rsplit("/", 1)[-1] for p in rep["files"])
    assert names == ["measurements.csv", "mesh.svg", "pattern.dxf"]
    rows = (out / "measurements.csv").read_text().splitlines()
    assert rows[0] == "piece,kind,name,pattern_mm,body_mm"
    assert any(row.startswith("mesh,width,elbow,") for row in rows)
    with pytest.raises(ValueError, match="fraction"):
        atelier.made_to_measure_pattern(tube(), str(tmp_path / "bad"), lines=[("waist", 2.0)])


def flared(r0=0.1, flare=0.3, h=0.4, squash=0.8, nu=24, nv=4):
    """tube()'s topology on another body: an elliptic cone, wider at y = 0."""
    v, f = tube(r0, h, nu, nv)
    grow = 1 + flare * (1 - v[:, 1] / h)
    return v * np.stack([grow, np.ones(len(v)), squash * grow], axis=1), f


def figures(rep):
    return ([(p["name"], p["mirrored"], p["height_mm"], p["widths_mm"]) for p in rep["pieces"]],
            [(s["joint"], s["lengths_mm"]) for s in rep["seams"]])


def test_made_to_measure_patterns_batch_form(tmp_path):
    # Prepared once on the reference garment, then written per body: on the
    # reference itself the same pieces and seams as the one-shot call (the
    # same figures to 1e-3 mm; cold, warm_start=False, the same numbers);
    # on other bodies of the same topology, the other body's measures: a
    # wider, taller tube opens into its own girth x height rectangle, and
    # an elliptic cone flattens without flips, its seam sides within the
    # tests' 2 mm.
    ref = tube()
    lines = [("elbow", 0.5), ("cuff", 0.1)]
    one = atelier.made_to_measure_pattern(ref, str(tmp_path / "one"), lines=lines)
    batch = atelier.MadeToMeasurePatterns(ref, lines=lines)
    warm = batch.write(ref, str(tmp_path / "warm"))
    assert warm["warm_started_pieces"] == 1 and one["warm_started_pieces"] == 0
    (mine, seams), (theirs, seams_one) = figures(warm), figures(one)
    assert [p[:2] for p in mine] == [p[:2] for p in theirs]
    assert [s[0] for s in seams] == [s[0] for s in seams_one]
    for p, q in zip(mine, theirs):
        assert p[2] == pytest.approx(q[2], abs=1e-3)
        assert p[3] == pytest.approx(q[3], abs=1e-3)
    for s, t in zip(seams, seams_one):
        assert np.allclose(s[1], t[1], atol=1e-3)
    cold = atelier.MadeToMeasurePatterns(ref, lines=lines, warm_start=False).write(ref, str(tmp_path / "cold"))
    assert cold["warm_started_pieces"] == 0 and figures(cold) == figures(one)
    assert sorted(p.rsplit("/", 1)[-1] for p in warm["files"]) == ["measurements.csv", "mesh.svg", "pattern.dxf"]

    r, h, nu = 0.13, 0.47, 24
    big = batch.write(tube(r, h), str(tmp_path / "big"))
    assert big["flipped"] == 0 and big["failed_seams"] == 0 and big["warm_started_pieces"] == 1
    (piece,) = big["pieces"]
    girth = 1000 * nu * 2 * r * np.sin(np.pi / nu)
    assert piece["height_mm"] == pytest.approx(1000 * h, abs=1e-6)
    assert piece["widths_mm"]["elbow"] == pytest.approx(girth, abs=1e-6)
    (seam,) = big["seams"]
    assert [a for a, _ in seam["lengths_mm"]] == pytest.approx([1000 * h, 1000 * h], abs=1e-6)

    cone = batch.write(flared(), str(tmp_path / "cone"))
    assert cone["flipped"] == 0 and cone["failed_seams"] == 0
    assert cone["max_seam_difference_mm"] < 2.0
    alone = atelier.made_to_measure_pattern(flared(), str(tmp_path / "cone_one"), lines=lines)
    assert cone["max_seam_difference_mm"] <= alone["max_seam_difference_mm"] + 0.1
    for a, b in zip(cone["pieces"], alone["pieces"]):  # the same body measured: heights within 1 mm
        assert a["height_mm"] == pytest.approx(b["height_mm"], abs=1.0)

    with pytest.raises(ValueError, match="topology"):
        batch.write(tube(nu=20), str(tmp_path / "other"))


def test_made_to_measure_patterns_from_several_threads(tmp_path):
    # write() releases the GIL and may run for several bodies at once: the
    # same figures as one body at a time, in any order.
    from concurrent.futures import ThreadPoolExecutor

    batch = atelier.MadeToMeasurePatterns(tube(), svg=False, dxf=False)
    bodies = [flared(flare=0.1 * k, squash=1 - 0.05 * k) for k in range(4)]
    alone = [figures(batch.write(b, str(tmp_path / f"a{k}"), threads=1)) for k, b in enumerate(bodies)]
    with ThreadPoolExecutor(2) as pool:
        together = list(pool.map(lambda k: figures(batch.write(bodies[k], str(tmp_path / f"t{k}"), threads=2)),
                                 reversed(range(4))))
    assert together[::-1] == alone


def test_prepare_made_to_measure_patterns_writes_the_clis_files(scratch):
    # prepare_made_to_measure_patterns is what `atelier regen --patterns`
    # calls in a job of 8 bodies or more (the skirt regenerated and prepared
    # on the reference body): with the bodies regenerated by
    # regenerate_profiles, every pattern file the same bytes as the CLI's.
    run_cli("encode", "--template", "skirt", "--reference", "mannequin", "--out", scratch / "t")
    run_cli("--seed", 3, "regen", "--template", scratch / "t" / "skirt.template.json", "--source", "mannequin",
            "--count", 8, "--levels", 1, "--patterns", "--out", scratch / "run")
    mannequin = atelier.Mannequin()
    reference = mannequin.reference()
    skirt = atelier.read_profile_template(scratch / "t" / "skirt.template.json")
    bodies = mannequin.positions(atelier.sample_mannequins(8, 3), dtype=np.float32)
    regen = atelier.regenerate_profiles(skirt, reference, bodies, levels=1)
    (batch,) = atelier.prepare_made_to_measure_patterns(skirt, reference, levels=1)
    assert batch.prepared and batch.reason is None
    for b in (0, 7):
        ours = scratch / "ours" / str(b)
        rep = batch.write(regen.meshes[b][0], str(ours))
        body = scratch / "run" / "bodies" / f"mannequin-{b:05d}"
        record = json.loads((body.parent / f"mannequin-{b:05d}.json").read_text())["patterns"]["skirt"]
        assert rep["warm_started_pieces"] == record["warm_started_pieces"] == 1
        theirs = sorted((body / "patterns" / "skirt").iterdir())
        assert [f.name for f in theirs] == sorted(f.name for f in ours.iterdir())
        for f in theirs:
            assert (ours / f.name).read_bytes() == f.read_bytes(), (b, f.name)
    with pytest.raises(ValueError, match="named line 'knee'"):
        atelier.prepare_made_to_measure_patterns(skirt, reference, lines=[("knee", 2.0)])
    with pytest.raises(ValueError, match="encoded on a reference body"):
        other = atelier.Mannequin(2).reference()
        atelier.prepare_made_to_measure_patterns(skirt, other)
