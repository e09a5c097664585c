"""Import pybullet without its build-time banner on standard output.

pybullet's C code prints "pybullet build time: ..." through C stdio, which is
flushed at exit, after everything Python printed; that would break commands
whose last line of output must be JSON. Importing it here with file
descriptor 1 pointed at /dev/null (and C stdio flushed) keeps stdout clean.
"""

from __future__ import annotations

import ctypes
import os
import sys


def _quiet_import():
    if "pybullet" in sys.modules:
        return sys.modules["pybullet"]
    sys.stdout.flush()
    saved = os.dup(1)
    try:
        with open(os.devnull, "w") as devnull:
            os.dup2(devnull.fileno(), 1)
            import pybullet as module

            ctypes.CDLL(None).fflush(None)
    finally:
        os.dup2(saved, 1)
        os.close(saved)
    return module


pybullet = _quiet_import()
