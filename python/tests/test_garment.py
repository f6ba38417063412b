"""The garment pipeline through Python: batches, layers, fit figures, thread
counts, progress and cancellation, zero-copy results."""
import os
import signal
import threading

import numpy as np
import pytest

import atelier
from conftest import top_band


def test_regenerate_a_batch(small):
    shorts, bodies = small["shorts"], small["bodies"]
    res = atelier.regenerate(shorts, bodies)
    assert len(res) == len(bodies) and res.names == ["shorts"]
    pos, q = res.positions[0], res.quality[0]
    assert pos.shape == (len(bodies), shorts.vertex_count, 3) and pos.dtype == np.float64
    assert res.ok.all() and res.errors == [None] * len(bodies)
    assert (q["ok"]).all() and (q["vertices"] == shorts.vertex_count).all()
    assert (q["inside"] == 0).all()  # the collision pass leaves nothing inside
    assert (q["min_clearance"] > 0).all() and (q["strain_p95"] < 1).all()
    # clearance_change: the mean clearance minus the mean on the reference body.
    ref = float(np.mean(shorts.reference_clearance.astype(np.float64)))
    assert np.allclose(q["clearance_change"], q["mean_clearance"] - ref)
    # Each body's garment follows its body: not the reference positions, and
    # different bodies give different garments.
    assert not np.allclose(pos[0], shorts.vertices)
    assert not np.allclose(pos[0], pos[1])
    # Strain recomputed from the arrays agrees with the engine's figure.
    e = shorts.edges
    for b in range(2):
        length = np.linalg.norm(pos[b][e[:, 0]] - pos[b][e[:, 1]], axis=1)
        strain = np.abs(length / shorts.rest_length - 1)
        assert np.isclose(strain.max(), q["strain_max"][b], rtol=0, atol=1e-12)


def test_thread_counts_and_chunks_give_the_same_bits(small):
    shorts, bodies = small["shorts"], small["bodies"]
    one = atelier.regenerate(shorts, bodies, threads=1)
    two = atelier.regenerate(shorts, bodies, threads=2, chunk=4)
    per_body = atelier.regenerate(shorts, bodies, threads=2, chunk=1)
    for other in (two, per_body):
        assert one.positions[0].tobytes() == other.positions[0].tobytes()
        assert one.quality[0].tobytes() == other.quality[0].tobytes()
    # float64 bodies give the same results as float32 ones (the body set
    # stores floats), and float32 output is the float64 output rounded.
    f64 = atelier.regenerate(shorts, bodies.astype(np.float64), dtype="float32")
    assert np.array_equal(f64.positions[0], one.positions[0].astype(np.float32))


def test_a_saved_template_reads_back_identical(small, scratch):
    shorts, family = small["shorts"], small["family"]
    shorts.save(scratch)
    assert (scratch / "shorts.atd").exists() and (scratch / "shorts.obj").exists()
    back = atelier.read_garment_template(family, scratch / "shorts.atd")
    assert back.name == "shorts" and back.vertex_count == shorts.vertex_count
    assert np.array_equal(back.vertices, shorts.vertices)
    bodies = small["bodies"][:2]
    assert atelier.regenerate(back, bodies).positions[0].tobytes() == atelier.regenerate(shorts, bodies).positions[0].tobytes()
    with pytest.raises(FileNotFoundError):
        atelier.read_garment_template(family, scratch / "none.atd")


def test_layers(small):
    body, family, shorts, bodies = small["body"], small["family"], small["shorts"], small["bodies"][:3]
    wrap = atelier.encode_garment(family, top_band(body, offset=0.004), name="wrap", z_depth=1)
    assert wrap.z_depth == 1
    regen = atelier.Regenerator([shorts, wrap])
    layered = regen.run(bodies)
    assert layered.names == ["shorts", "wrap"]
    assert [p.shape[1] for p in layered.positions] == [shorts.vertex_count, wrap.vertex_count]
    apart = atelier.Regenerator([shorts, wrap], layers=False).run(bodies)
    # The wrap sits 4 mm out over the shorts' 8 mm: resolving the layers moves it.
    assert not np.array_equal(layered.positions[1], apart.positions[1])
    assert (layered.quality[1]["inside"] == 0).all()
    # Swapped, the wrap is the inner layer: nothing pushes it out any more.
    swapped = atelier.Regenerator([shorts.with_z_depth(2), wrap]).run(bodies)
    assert not np.array_equal(swapped.positions[1], layered.positions[1])
    with pytest.raises(ValueError, match="different GarmentFamily"):
        atelier.Regenerator([shorts, atelier.encode_garment(atelier.GarmentFamily(body), top_band(body))])


def test_layer_inside_counts_the_outer_garment_under_the_inner_one(small):
    # Issue 26: the layer-inside counter (count_inside_layer) per body and
    # garment. The wrap (outer, z_depth 1) is cut 4 mm off the skin, inside
    # the shorts (8 mm) where they overlap: decoded without the collision
    # pass the counter finds its vertices under the shorts; with the layers
    # resolved none is left. The inner layer is never counted.
    body, family, shorts, bodies = small["body"], small["family"], small["shorts"], small["bodies"][:3]
    wrap = atelier.encode_garment(family, top_band(body, offset=0.004), name="wrap", z_depth=1)
    apart = atelier.Regenerator([shorts, wrap], collision_pass=False).run(bodies)
    layered = atelier.Regenerator([shorts, wrap]).run(bodies)
    for run in (apart, layered):
        assert run.quality[1]["layer_inside"].dtype == np.uint64
        assert (run.quality[0]["layer_inside"] == 0).all()
    assert (apart.quality[1]["layer_inside"] > 0).all()
    assert (apart.quality[1]["layer_inside"] <= wrap.vertex_count).all()
    assert (layered.quality[1]["layer_inside"] == 0).all()
    # Not layered: not counted.
    assert (atelier.Regenerator([shorts, wrap], layers=False).run(bodies).quality[1]["layer_inside"] == 0).all()


def test_run_one_moves_the_engine_vector_into_the_array(small):
    shorts, bodies = small["shorts"], small["bodies"]
    regen = atelier.Regenerator(shorts)
    [(pos, quality)] = regen.run_one(bodies[0])
    assert pos.shape == (shorts.vertex_count, 3) and pos.flags.owndata is False
    assert type(pos.base).__name__ == "PyCapsule"  # owns the moved std::vector: no copy
    assert quality["ok"] and quality["inside"] == 0
    batch = regen.run(bodies[:1])
    assert np.allclose(pos, batch.positions[0][0], atol=1e-6)


def test_fit_figures(small):
    shorts, family, body, bodies = small["shorts"], small["family"], small["body"], small["bodies"][:2]
    res = atelier.regenerate(shorts, bodies, fit=True)
    q = res.quality[0]
    assert np.isfinite(q["clearance_change_rms"]).all() and np.isfinite(q["excess_strain_p95"]).all()
    assert np.isnan(atelier.regenerate(shorts, bodies).quality[0]["clearance_change_rms"]).all()
    # The same figure from measure_fit on the arrays.
    tris = body.triangles
    fit = atelier.measure_fit(
        (bodies[1].astype(np.float64), tris),
        (res.positions[0][1], shorts.faces),
        source_garment=shorts.vertices,
        source_body=body.vertices,
    )
    assert fit["inside"] == q["inside"][1]
    assert np.isclose(fit["clearance_change_rms"], q["clearance_change_rms"][1], rtol=1e-12)


def test_progress_reports_bodies(small):
    seen = []
    atelier.regenerate(small["shorts"], small["bodies"], chunk=2, progress=lambda *a: seen.append(a))
    assert seen[-1] == ("bodies", 6, 6)
    assert [d for _, d, _ in seen] == sorted(d for _, d, _ in seen)


def test_an_exception_in_the_callback_cancels(small):
    regen = atelier.Regenerator(small["shorts"])

    class Stop(Exception):
        pass

    def stop(stage, done, total):
        if done >= 1:
            raise Stop()

    with pytest.raises(Stop):
        regen.run(small["bodies"], chunk=1, threads=1, progress=stop)
    # The regenerator is still usable and gives the same bits.
    assert regen.run(small["bodies"][:2]).positions[0].tobytes() == atelier.regenerate(small["shorts"], small["bodies"][:2]).positions[0].tobytes()


def test_ctrl_c_cancels_through_the_engine(small):
    # A real SIGINT, sent from another thread while the engine works: the
    # waiting thread's signal check raises KeyboardInterrupt and cancels the
    # engine (ExecContext::cancel), which stops long before the end.
    # Judged by the work done, not by the clock (a loaded machine stretches
    # both runs): the job is long (about 1 s) next to the 50 ms timer.
    bodies = np.repeat(small["bodies"], 60, axis=0)
    regen = atelier.Regenerator(small["shorts"])
    calls = []

    def progress(stage, done, total):
        calls.append(done)
        if len(calls) == 1:  # the signal arrives after the callback returned, while the engine works
            threading.Timer(0.05, os.kill, (os.getpid(), signal.SIGINT)).start()

    with pytest.raises(KeyboardInterrupt):
        regen.run(bodies, chunk=1, threads=1, progress=progress)
    assert max(calls) < len(bodies)


def test_scaled_frames_follow_the_size_of_the_body(small, scratch):
    """encode_garment(scaled_frames=True) (`encode --scaled-frames`): on the
    reference body the same shorts as the paper's unit frames; on the body
    scaled by 1.25 about the origin, shorts nearer the shorts scaled by 1.25
    (offsets grow with the body; the decoder alone is exact there: the C++
    ScaledFrames tests); the flag survives a save."""
    body, family = small["body"], small["family"]
    v, f = small["shorts_mesh"]
    v32 = np.asarray(v, dtype=np.float32)
    unit = atelier.encode_garment(family, v32, f, name="shorts")
    scaled = atelier.encode_garment(family, v32, f, name="shorts", scaled_frames=True)
    ref = np.asarray(body.vertices, dtype=np.float64)[None]
    a = np.asarray(atelier.regenerate(unit, ref).positions[0], dtype=np.float64)
    b = np.asarray(atelier.regenerate(scaled, ref).positions[0], dtype=np.float64)
    assert np.abs(a - b).max() < 1e-6  # the scale is 1 to rounding there (float32 results)
    s = 1.25
    big = s * ref
    want = s * v32.astype(np.float64)
    err = {}
    for tag, g in (("unit", unit), ("scaled", scaled)):
        r = atelier.regenerate(g, big)
        assert r.ok.all()
        err[tag] = np.linalg.norm(np.asarray(r.positions[0], dtype=np.float64) - want, axis=1).mean()
    assert err["scaled"] < 0.8 * err["unit"], err
    scaled.save(scratch)
    back = atelier.read_garment_template(family, scratch / "shorts.atd")
    assert np.array_equal(atelier.regenerate(back, big).positions[0], atelier.regenerate(scaled, big).positions[0])
