"""The binding regenerates the same positions as the CLI for the same inputs,
bit for bit: `atelier regen --template X.atd --source mannequin --count N
--meshes N --seed S` writes each body's garment as OBJ in float precision;
the binding regenerates the same garment on the same sampled mannequins
(sample_mannequins(N, S), what the CLI draws with --seed S) and its
float32 output must be those floats exactly."""
import numpy as np
import pytest

import atelier
from conftest import demo_shorts, run_cli, top_band

COUNT = 2
SEED = 5


@pytest.fixture(scope="module")
def job(tmp_path_factory):
    """The CLI's reference body (the default mannequin, level 6), its family,
    the sampled bodies, and the demo's shorts encoded by the binding from
    float32 vertices and saved where the CLI reads templates."""
    mannequin = atelier.Mannequin()  # the CLI's resolution
    body = mannequin.reference()
    family = atelier.GarmentFamily(body)
    bodies = mannequin.positions(atelier.sample_mannequins(COUNT, SEED), dtype=np.float32)
    v, f = demo_shorts(body)
    shorts = atelier.encode_garment(family, v.astype(np.float32), f, name="shorts")
    templates = tmp_path_factory.mktemp("templates")
    shorts.save(templates)
    return body, family, bodies, shorts, templates


def obj_floats(path):
    v, _ = atelier.read_mesh(path)
    return v.astype(np.float32)  # the file holds floats ("%.9g"): exact


def test_binding_encode_cli_regen_binding_regen_same_bits(job, scratch):
    _, family, bodies, shorts, templates = job
    run_cli("--threads", 1, "--seed", SEED, "regen", "--template", templates / "shorts.atd",
            "--source", "mannequin", "--count", COUNT, "--meshes", COUNT, "--out", scratch / "run")
    # The binding on the template read back from the same files.
    template = atelier.read_garment_template(family, templates / "shorts.atd")
    ours = atelier.regenerate(template, bodies, dtype=np.float32, threads=2)
    assert ours.ok.all()
    for b in range(COUNT):
        theirs = obj_floats(scratch / "run" / "bodies" / f"mannequin-{b:05d}" / "shorts.obj")
        assert theirs.shape == ours.positions[0][b].shape
        assert np.array_equal(theirs.view(np.uint32), ours.positions[0][b].view(np.uint32)), f"body {b}"
    # The in-memory template (encoded from float32 vertices) gives the same bits.
    direct = atelier.regenerate(shorts, bodies, dtype=np.float32)
    assert direct.positions[0].tobytes() == ours.positions[0].tobytes()


def test_cli_encode_and_layers_same_bits(job, scratch):
    body, family, bodies, _, templates = job
    # A second garment as an OBJ file, encoded by the CLI (`encode --garment`),
    # worn over the shorts: the CLI regenerates both as layers.
    w, wf = top_band(body, offset=0.004)
    atelier.write_mesh(scratch / "wrap.obj", w.astype(np.float32), wf)
    run_cli("encode", "--garment", scratch / "wrap.obj", "--reference", "mannequin", "--out", scratch / "t")
    run_cli("--threads", 2, "--seed", SEED, "regen", "--template", templates / "shorts.atd",
            "--template", scratch / "t" / "wrap.atd", "--source", "mannequin", "--count", COUNT,
            "--meshes", COUNT, "--out", scratch / "run")
    shorts = atelier.read_garment_template(family, templates / "shorts.atd")
    wrap = atelier.read_garment_template(family, scratch / "t" / "wrap.atd")
    ours = atelier.regenerate([shorts, wrap], bodies, dtype=np.float32, threads=1)
    for b in range(COUNT):
        for g, name in enumerate(("shorts", "wrap")):
            theirs = obj_floats(scratch / "run" / "bodies" / f"mannequin-{b:05d}" / f"{name}.obj")
            assert np.array_equal(theirs.view(np.uint32), ours.positions[g][b].view(np.uint32)), (b, name)
