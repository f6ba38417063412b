"""Progress and cancellation of the modelling calls (issue 25): every long
call relays the engine's stage reports to `progress(stage, done, total)`, the
last report being its final stage, and an exception raised by the callback
propagates (the engine is cancelled through its ExecContext)."""
import numpy as np
import pytest

import atelier
from test_curvenet import cube_curves
from test_net import A, B, plane_and_ellipse
from test_pattern import grid
from test_sketch import sphere, strokes


def record():
    seen = []
    return seen, lambda stage, done, total: seen.append((stage, done, total))


def check_reports(seen, prefix, final):
    assert seen, "no progress report"
    assert all(s.startswith(prefix) for s, _, _ in seen), seen
    assert all(0 <= d <= t for _, d, t in seen), seen
    assert [d for s, d, _ in seen if s == seen[-1][0]] == sorted(d for s, d, _ in seen if s == seen[-1][0])
    assert seen[-1] == final


@pytest.mark.parametrize("threads", [1, 2])
def test_boolean_trim_and_round_off_report_their_stages(threads):
    seen, cb = record()
    v, f, rep = atelier.boolean(A, B, threads=threads, progress=cb)
    check_reports(seen, "boolean: ", ("boolean: result", 5, 5))
    seen, cb = record()
    pv, pf, curve = plane_and_ellipse()
    atelier.trim((pv, pf), curve, threads=threads, progress=cb)
    check_reports(seen, "trim: ", ("trim: result", 3, 3))
    seen, cb = record()
    atelier.round_off((v, f), rep["seam"], rings=1, threads=threads, progress=cb)
    check_reports(seen, "round: ", ("round: result", 3, 3))


def test_surface_flatten_and_sketch_report_their_stages():
    seen, cb = record()
    atelier.surface_from_curves(cube_curves(), levels=2, progress=cb)
    check_reports(seen, "surface: ", ("surface: distances", 7, 7))
    seen, cb = record()
    v, f = grid()
    atelier.flatten((v, f), progress=cb)
    check_reports(seen, "flatten: ", ("flatten: pieces", 1, 1))
    seen, cb = record()
    sv, sf = sphere()
    atelier.sketch((sv, sf), strokes(0.03), progress=cb)
    assert seen and seen[-1][0] == "sketch: strokes" and seen[-1][1] == seen[-1][2] >= 1


def test_an_exception_in_a_modelling_callback_propagates_and_the_call_can_run_again():
    class Stop(Exception):
        pass

    def stop(stage, done, total):
        raise Stop(stage)

    with pytest.raises(Stop):
        atelier.boolean(A, B, progress=stop)
    with pytest.raises(Stop):
        atelier.surface_from_curves(cube_curves(), levels=1, progress=stop)
    # Nothing is left cancelled: the same calls give the same bits afterwards.
    v1, f1, _ = atelier.boolean(A, B)
    v2, f2, _ = atelier.boolean(A, B, threads=1)
    assert np.asarray(v1).tobytes() == np.asarray(v2).tobytes()
