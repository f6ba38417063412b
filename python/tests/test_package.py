"""The package: docstrings and type stubs cover the API, and `cmake --install`
puts a package the system python3 imports."""
import ast
import os
import pathlib
import pydoc
import subprocess
import sys

import pytest

import atelier

STUBS = pathlib.Path(atelier.__file__).with_name("_atelier.pyi")


def public_names():
    return sorted(n for n in dir(atelier._atelier) if not n.startswith("_"))


def test_help_of_regenerate_reads_well():
    text = pydoc.render_doc(atelier.regenerate, renderer=pydoc.plaintext)
    for phrase in ("garments", "bodies: (B, n, 3)", "threads", "progress", "KeyboardInterrupt", "Regeneration",
                   "bit", "ValueError"):
        assert phrase in text, phrase
    # Argument names and readable types, not arg0 or pybind11's "handle".
    assert "regenerate(garments: GarmentTemplate | list[GarmentTemplate], bodies: numpy.ndarray, *, layers" in text
    assert "progress: Callable[[str, int, int], None] | None = None" in text
    assert "handle" not in text


def test_every_public_name_has_a_docstring_and_a_stub():
    tree = ast.parse(STUBS.read_text())
    stubbed = {n.name for n in tree.body if isinstance(n, (ast.FunctionDef, ast.ClassDef))}
    stubbed |= {t.id for n in tree.body if isinstance(n, ast.Assign) for t in n.targets if isinstance(t, ast.Name)}
    stubbed |= {n.target.id for n in tree.body if isinstance(n, ast.AnnAssign)}
    for name in public_names():
        assert name in stubbed, f"{name} has no stub in {STUBS.name}"
        assert (getattr(atelier, name).__doc__ or "").strip(), f"{name} has no docstring"
    # Methods and properties of the classes too.
    classes = {n.name: n for n in tree.body if isinstance(n, ast.ClassDef)}
    for cname, node in classes.items():
        members = {m.name for m in node.body if isinstance(m, ast.FunctionDef)}
        members |= {m.target.id for m in node.body if isinstance(m, ast.AnnAssign)}
        cls = getattr(atelier, cname)
        for member in dir(cls):
            if member.startswith("_") and member not in ("__init__", "__iter__", "__len__"):
                continue
            if member in ("__init__", "__iter__", "__len__") and member not in cls.__dict__:
                continue
            if member == "__init__" and (cls.__init__.__doc__ or "").startswith("Initialize self"):
                continue  # no constructor: made by functions
            assert member in members, f"{cname}.{member} has no stub"


def test_install_puts_an_importable_package(scratch):
    build = pathlib.Path(os.environ.get("ATELIER_BUILD_DIR", ""))
    if not (build / "CMakeCache.txt").exists():
        pytest.skip("ATELIER_BUILD_DIR is not set (run the suite through ctest)")
    prefix = scratch.resolve() / "prefix"
    r = subprocess.run(["cmake", "--install", str(build), "--prefix", str(prefix), "--component", "python"],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr
    cache = (build / "CMakeCache.txt").read_text()
    rel = next(l.split("=", 1)[1] for l in cache.splitlines() if l.startswith("ATELIER_PYTHON_INSTALL_DIR:"))
    site = prefix / rel
    for f in ("__init__.py", "_atelier.pyi", "py.typed"):
        assert (site / "atelier" / f).exists(), f
    env = dict(os.environ, PYTHONPATH=str(site))
    r = subprocess.run([sys.executable, "-c", "import atelier; print(atelier.__file__); print(atelier.__version__)"],
                       capture_output=True, text=True, env=env, cwd=scratch)
    assert r.returncode == 0, r.stderr
    assert r.stdout.splitlines()[0].startswith(str(site))
    # With the default prefix the directory is on this interpreter's own
    # path: `cmake --install` alone makes `import atelier` work.
    default = pathlib.Path(next(l.split("=", 1)[1] for l in cache.splitlines()
                                if l.startswith("CMAKE_INSTALL_PREFIX:")))
    assert str(default / rel) in sys.path or str(default) != "/usr/local"
