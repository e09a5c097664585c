"""Listening to the simulation's steps: a call after every ``pybullet.stepSimulation`` of one client.

The arm, the recipe world and the benchmarks all step PyBullet themselves, and
PyBullet offers no step callback. While at least one listener is registered,
``pybullet.stepSimulation`` is wrapped by a function that calls the original
and then the listeners of the client that was stepped, in the thread that
stepped it (the only thread that may read that client at that moment). The
original is restored when the last listener goes. A listener that raises is
dropped (with a warning) so that it can never stop the simulation.
"""

from __future__ import annotations

import sys
import threading

import pybullet

_lock = threading.Lock()
_listeners: dict[int, list] = {}
_original = None


def _tapped_step(*args, **kwargs):
    result = _original(*args, **kwargs)
    client = kwargs.get("physicsClientId", args[0] if args else 0)
    for listener in tuple(_listeners.get(client, ())):
        try:
            listener()
        except Exception as error:  # a viewer must never stop the simulation
            print(f"viewer: stopped following the simulation ({type(error).__name__}: {error})", file=sys.stderr)
            remove_step_listener(client, listener)
    return result


def add_step_listener(client: int, listener) -> None:
    """Call ``listener()`` after every step of PyBullet client ``client``."""
    global _original
    with _lock:
        if _original is None:
            _original = pybullet.stepSimulation
            pybullet.stepSimulation = _tapped_step
        _listeners.setdefault(client, []).append(listener)


def remove_step_listener(client: int, listener) -> None:
    """Stop calling ``listener``; restore PyBullet's own step when no listener is left."""
    global _original
    with _lock:
        listeners = _listeners.get(client, [])
        if listener in listeners:
            listeners.remove(listener)
        if not listeners:
            _listeners.pop(client, None)
        if not _listeners and _original is not None:
            if pybullet.stepSimulation is _tapped_step:
                pybullet.stepSimulation = _original
            _original = None


def is_tapped() -> bool:
    return pybullet.stepSimulation is _tapped_step
