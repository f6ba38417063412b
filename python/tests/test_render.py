"""Pictures: a body and its garment rendered to an array and a PNG; a
cancelled render leaves no file."""
import os
import signal
import threading

import numpy as np
import pytest

import atelier


def test_render_body_and_garment(small, scratch):
    body, shorts, bodies = small["body"], small["shorts"], small["bodies"]
    res = atelier.regenerate(shorts, bodies[:1])
    garment = (res.positions[0][0], shorts.faces)
    b0 = body.with_positions(bodies[0].astype(np.float64))
    img = atelier.render(b0, garment, width=60, height=80, path=scratch / "pic.png", threads=2)
    assert img.shape == (80, 60, 3) and img.dtype == np.uint8
    assert np.array_equal(atelier.read_png(scratch / "pic.png"), img)
    # The garment shows: with it, some pixels differ from the body alone.
    alone = atelier.render(b0, width=60, height=80)
    assert (np.abs(img.astype(int) - alone.astype(int)).sum(axis=2) > 30).sum() > 20
    # Same pixels for any thread count; the background is white.
    assert np.array_equal(img, atelier.render(b0, [garment], width=60, height=80, threads=1))
    assert (img[0, 0] == 255).all()
    both = atelier.render(b0, garment, width=60, height=80, view="both")
    assert both.shape == (80, 2 * 60 + 8, 3)
    with pytest.raises(ValueError, match="view"):
        atelier.render(b0, view="top")


def test_a_cancelled_render_leaves_no_file(small, scratch):
    body = small["body"]
    path = scratch / "big.png"

    def stop(stage, done, total):
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        atelier.render(body, width=1200, height=1600, supersample=2, path=path, threads=1, progress=stop)
    assert list(scratch.iterdir()) == []  # neither the PNG nor a temporary file

    sent = []

    def interrupt(stage, done, total):  # a real SIGINT, from another thread, while the engine renders
        if not sent:
            sent.append(threading.Timer(0.05, os.kill, (os.getpid(), signal.SIGINT)))
            sent[0].start()

    with pytest.raises(KeyboardInterrupt):
        atelier.render(body, width=1200, height=1600, supersample=2, path=path, threads=1, progress=interrupt)
    assert list(scratch.iterdir()) == []
