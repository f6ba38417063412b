"""Profile templates: JSON round trips, regeneration on bodies, the same
meshes as the CLI."""
import numpy as np
import pytest

import atelier
from conftest import run_cli


@pytest.fixture(scope="module")
def templates(small):
    return atelier.project_templates(small["body"])


def test_project_templates_and_json_round_trip(templates, scratch):
    assert [t.name for t in templates] == ["top", "skirt", "trousers"]
    skirt = templates[1]
    assert skirt.profile_count > 0 and skirt.levels >= 1
    skirt.save(scratch / "skirt.template.json")
    back = atelier.read_profile_template(scratch / "skirt.template.json")
    assert back.to_json() == skirt.to_json()
    assert atelier.ProfileTemplate.from_json(skirt.to_json()).to_json() == skirt.to_json()
    mesh = skirt.mesh
    mesh.validate()
    assert mesh.vertex_count > 0
    bad = scratch / "bad.template.json"
    bad.write_text('{"format": "atelier-template", "version": 1, "name": 3}')
    with pytest.raises(ValueError, match=r"bad\.template\.json"):
        atelier.read_profile_template(bad)
    with pytest.raises(FileNotFoundError):
        atelier.read_profile_template(scratch / "none.template.json")


def test_regenerate_profiles(templates, small):
    body, bodies = small["body"], small["bodies"][:2]
    skirt = templates[1]
    res = atelier.regenerate_profiles(skirt, body, bodies, levels=1, threads=2)
    assert res.names == ["skirt"] and res.ok.all()
    q = res.quality[0]
    assert (q["inside"] == 0).all() and (q["crack"] < 1e-9).all()
    for b in range(2):
        mesh = res.meshes[b][0]
        mesh.validate()
        assert mesh.face_count == q["faces"][b]
    again = atelier.regenerate_profiles([skirt], body, bodies, levels=1, threads=1)
    for b in range(2):
        assert res.meshes[b][0].vertices.tobytes() == again.meshes[b][0].vertices.tobytes()
    one = atelier.regenerate_profiles(skirt, body, bodies[0], levels=1)
    assert one.meshes[0][0].vertices.tobytes() == res.meshes[0][0].vertices.tobytes()
    other = atelier.Mannequin(2).reference()
    with pytest.raises(ValueError, match="encoded on a reference body"):
        atelier.regenerate_profiles(skirt, other, other.vertices)


def test_profile_regeneration_matches_the_cli(scratch):
    run_cli("encode", "--template", "skirt", "--reference", "mannequin", "--out", scratch / "t")
    run_cli("--seed", 3, "regen", "--template", scratch / "t" / "skirt.template.json", "--source", "mannequin",
            "--count", 2, "--meshes", 2, "--levels", 1, "--out", scratch / "run")
    mannequin = atelier.Mannequin()
    skirt = atelier.read_profile_template(scratch / "t" / "skirt.template.json")
    bodies = mannequin.positions(atelier.sample_mannequins(2, 3), dtype=np.float32)
    ours = atelier.regenerate_profiles(skirt, mannequin.reference(), bodies, levels=1)
    for b in range(2):
        # The same model: written by the same writer, the same bytes.
        atelier.write_mesh(scratch / f"ours-{b}.obj", ours.meshes[b][0])
        theirs = scratch / "run" / "bodies" / f"mannequin-{b:05d}" / "skirt.obj"
        assert (scratch / f"ours-{b}.obj").read_bytes() == theirs.read_bytes(), b
