"""Atelier: bodies, garments and templates as numpy arrays.

The Python binding of the Atelier geometry engine (docs/python.md). The
compiled extension ``atelier._atelier`` holds everything; this package
re-exports it. Build it with ``make python`` and run with Debian's
interpreter, whose NumPy the module is built against:

    PYTHONPATH=build/python /usr/bin/python3 examples/pipeline.py
"""
from ._atelier import *  # noqa: F401,F403
from ._atelier import __doc__, __version__  # noqa: F401

__all__ = [name for name in dir() if not name.startswith("_")]
