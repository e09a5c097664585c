"""Importing PyBullet without its banner.

PyBullet's C module writes ``pybullet build time: ...`` to standard error when
it is first imported, so every command's output (and every error message a
test reads) would open with it. The first import happens here, with the
process's standard error pointed at /dev/null for that moment; later imports
are cached and write nothing. ``bullet_world`` imports this before anything
else, and ``robot`` imports ``bullet_world`` first.
"""

from __future__ import annotations

import os
import sys


def import_pybullet_quietly():
    """Import and return the ``pybullet`` module, its banner swallowed."""
    if "pybullet" in sys.modules:
        return sys.modules["pybullet"]
    sys.stderr.flush()
    try:
        saved = os.dup(2)
    except OSError:  # no standard error at all: nothing to keep clean
        import pybullet
        return pybullet
    try:
        with open(os.devnull, "wb") as null:
            os.dup2(null.fileno(), 2)
            import pybullet
    finally:
        os.dup2(saved, 2)
        os.close(saved)
    return pybullet
