"""A meshcat mirror of the PyBullet kitchen, with the dialog drawn into it (see docs/viewer.md).

:class:`Viewer` follows one :class:`~bullet_world.world.World`: every body's
shape, size and colour read from PyBullet (the counter, the objects, the
Panda's link meshes), the kitchen's semantic locations as labelled regions,
object numbers floating above the objects, and, when it observes a dialog,
the object a question is about (highlighted), the question and the answer.

Threads: PyBullet is read only in the thread that steps it (after each step,
through :mod:`bullet_world.viewer.tap`, and at dialog events); meshcat is
called only from the viewer's own thread (:mod:`bullet_world.viewer.thread`).
Live frames are published at most ``live_fps`` times per wall-clock second;
recorded frames are taken every ``1 / fps`` simulated seconds.
"""

from __future__ import annotations

import sys
import textwrap
import time
from functools import lru_cache
from pathlib import Path

import numpy as np
import pybullet as p

from bullet_world.viewer.recording import Recording, export_html
from bullet_world.viewer.scene import Frame, Look, WorldReader, translation
from bullet_world.viewer.server import ViewerError
from bullet_world.viewer.tap import add_step_listener, remove_step_listener
from bullet_world.viewer.thread import MeshcatThread
from bullet_world.viewpoint import Viewpoint
from learning.errors import SettingsError

DWELL_S = {"scene": 1.0, "question": 1.2, "answer": 1.8, "quiet": 0.6}  # pauses in the recording's time
ASKED_RGBA = (1.0, 0.82, 0.0, 0.35)
SHOWN_RGBA = (0.1, 0.75, 0.3, 0.35)
REGION_RGBA = ((0.9, 0.3, 0.2), (0.2, 0.5, 0.95), (0.55, 0.3, 0.8), (0.95, 0.6, 0.1), (0.2, 0.7, 0.6),
               (0.8, 0.3, 0.6), (0.5, 0.5, 0.5))
LABEL_HEIGHT_M, TEXT_HEIGHT_M, REGION_LABEL_HEIGHT_M = 0.035, 0.055, 0.028
# In a page (no text panels: the page has the words) the number and location labels keep one size on the screen,
# as a share of the 3D view's height: about the page's text (tests/e2e/test_web_labels.py measures them).
SCREEN_LABEL_HEIGHT, SCREEN_REGION_LABEL_HEIGHT = 0.085, 0.1
LINE_CHARS, MAX_LINES = 56, 3


def default_camera(world) -> tuple[np.ndarray, np.ndarray]:
    """Eye and target of the teacher's view (:mod:`bullet_world.viewpoint`): across the counter from the robot,
    facing it, so the screen's left is the teacher's left, as in the questions' words and the scene pictures."""
    low, high = _counter_box(world)
    centre = np.array([(low[0] + high[0]) / 2, (low[1] + high[1]) / 2, high[2]])
    kitchen = getattr(world, "kitchen", None)
    if kitchen is not None and hasattr(kitchen, "robot_yaw"):
        viewpoint = Viewpoint.of_kitchen(kitchen)
    else:  # a bare world: face wherever the robot stands
        facing = _robot_xy(world, centre) - centre[:2]
        norm = float(np.linalg.norm(facing))
        facing = facing / norm if norm > 1e-6 else np.array([0.0, -1.0])
        viewpoint = Viewpoint((float(facing[0]), float(facing[1])), (float(centre[0]), float(centre[1])))
    target = centre + np.array([*(0.05 * np.asarray(viewpoint.facing)), 0.1])
    return viewpoint.eye(target, distance=1.0, height=0.75), target


def _counter_box(world) -> tuple[np.ndarray, np.ndarray]:
    body = getattr(world, "counter_body", None)
    if body is None:
        return np.array([-0.6, -0.5, -0.05]), np.array([0.6, 0.5, 0.0])
    low, high = p.getAABB(body, physicsClientId=world.client)
    return np.asarray(low), np.asarray(high)


def _robot_xy(world, fallback: np.ndarray) -> np.ndarray:
    base = getattr(getattr(world, "kitchen", None), "robot_base", None)
    if base is None:
        robot = getattr(getattr(world, "robot", None), "body_id", None)
        if robot is None:
            return fallback[:2] - np.array([0.0, 1.0])
        base = p.getBasePositionAndOrientation(robot, physicsClientId=world.client)[0]
    return np.asarray(base[:2], dtype=float)


def _action_fields(action) -> tuple[str, int | None, str | None]:
    """(kind, 0-based object index, concept) of an action object or a transcript action record."""
    if isinstance(action, dict):
        number = action.get("object")
        index = number - 1 if isinstance(number, int) else None
        return str(action.get("kind", "")), index, action.get("concept")
    index = getattr(action, "object_index", None)
    return str(getattr(action, "kind", "")), index if isinstance(index, (int, np.integer)) else None, \
        getattr(action, "concept", None)


@lru_cache(maxsize=4096)
def _text(text: str, style: str, height: float, screen: bool = False) -> tuple[Look, ...]:
    """The looks of one text sprite (cached: frames are built after every few simulation steps); ``screen``: a
    constant size on the screen, ``height`` a share of the view's height (``SCREEN_LABEL_HEIGHT``)."""
    return (Look("screen-text" if screen else "text", (height,), (1.0, 1.0, 1.0, 1.0), text=text, style=style),)


@lru_cache(maxsize=1024)
def _wrapped(text: str) -> str:
    """At most ``MAX_LINES`` lines of at most ``LINE_CHARS`` characters (an ellipsis where cut)."""
    lines = textwrap.wrap(" ".join(str(text).split()), LINE_CHARS) or [""]
    if len(lines) > MAX_LINES:
        lines = lines[:MAX_LINES]
        lines[-1] = lines[-1][: LINE_CHARS - 1] + "…"
    return "\n".join(lines)


class Viewer:
    """The live mirror (``live``) and/or an episode recording for a static HTML export (``record``).

    As a dialog observer it handles ``on_scene(scene)``, ``on_question(action, text, scene)``,
    ``on_answer(action, outcome, scene)`` and ``on_turn(record, scene)``; any of them may be missing.
    Raises :class:`ViewerError` when the live server can't start.
    """

    def __init__(self, world, *, live: bool = True, record: bool = False, export_path: str | Path | None = None,
                 camera: tuple | None = None, appearance=None, fps: int = 20, live_fps: float = 30.0,
                 panels: bool = True, start_timeout_s: float = 20.0, reply_timeout_s: float = 10.0):
        if fps < 1 or live_fps <= 0:
            raise SettingsError(f"the viewer needs fps >= 1 and live_fps > 0, got fps={fps}, live_fps={live_fps}")
        self.world, self.client = world, world.client
        self.reader = WorldReader(world, appearance)
        self.camera = camera if camera is not None else default_camera(world)
        self.export_path = Path(export_path) if export_path else None
        self.recording = Recording(fps) if (record or self.export_path) else None
        self.recording_started = False
        self.episode_time = 0.0
        self.question = self.answer = ""
        self.panels = panels  # the question and the answer as text in the scene (a page shows them beside it)
        self.asked: int | None = None
        self.shown: int | None = None
        self._asked_this_turn = False
        step = p.getPhysicsEngineParameters(physicsClientId=self.client)["fixedTimeStep"]
        self._step_s = float(step)
        self._steps_per_sample = max(1, int(round(1.0 / (fps * self._step_s))))
        self._steps = 0
        self._live_interval = 1.0 / live_fps
        self._last_live = -np.inf
        self._warned = False
        self._closed = False
        self._static = self._static_nodes()
        self._overlay_nodes: Frame = {}
        self._overlay_key: tuple = ()
        eye, target = (np.asarray(v, dtype=float) for v in self.camera)
        self._text_anchor = target + 0.5 * _unit_xy(eye - target) + np.array([0.0, 0.0, 0.12])  # the near edge
        forward = (target - eye) / max(float(np.linalg.norm(target - eye)), 1e-9)
        side = np.cross(forward, [0.0, 0.0, 1.0])
        self._screen_up = np.cross(side / max(float(np.linalg.norm(side)), 1e-9), forward)  # texts stack on screen
        self.url: str | None = None
        self.thread = MeshcatThread()
        if live:
            try:
                self.url = self.thread.start_live(self.camera, start_timeout_s, reply_timeout_s)
            except Exception as error:
                self.thread.stop()
                raise ViewerError(f"could not start the meshcat server: {error}") from None
        add_step_listener(self.client, self._after_step)
        try:
            self.update()
        except Exception:
            self.close()
            raise

    # -- following the simulation ------------------------------------------------------
    def _after_step(self) -> None:
        self._steps += 1
        if self.recording_started:
            self.episode_time += self._step_s
        sample = self.recording_started and self._steps % self._steps_per_sample == 0
        now = time.perf_counter()
        live = self.thread.live and now - self._last_live >= self._live_interval
        if not (sample or live):
            return
        frame = self.frame()
        if sample:
            self.recording.add(frame, self.episode_time)
        if live:
            self._publish(frame, now)

    def _publish(self, frame: Frame, now: float | None = None) -> None:
        self.thread.publish(frame)
        self._last_live = time.perf_counter() if now is None else now

    def frame(self, refresh: bool = False) -> Frame:
        """Every node now: the world's bodies, the kitchen's locations, numbers, highlight and texts."""
        frame = self.reader.frame(refresh)
        places = [self.reader.place(node) for node in self.reader.object_nodes]
        key = (tuple(self.reader.object_nodes), tuple(places), self.asked, self.shown, self.question, self.answer)
        if key != self._overlay_key or None in places:  # numbers and highlight move when an object moves (1 mm)
            self._overlay_nodes, self._overlay_key = self._overlay(), key
        frame.update(self._static)
        frame.update(self._overlay_nodes)
        return frame

    def update(self, dwell_s: float = 0.0) -> None:
        """Mirror the world now (re-reading which bodies exist); in a recording, then pause ``dwell_s``."""
        if self._closed or not p.isConnected(self.client):
            return
        self._check_live()
        frame = self.frame(refresh=True)
        if self.thread.live:
            self._publish(frame)
        if self.recording_started:
            self.recording.add(frame, self.episode_time)
            if dwell_s > 0:
                self.episode_time += dwell_s
                self.recording.add(frame, self.episode_time)

    def start_recording(self) -> None:
        """Begin the recording now (observers begin it at the first scene)."""
        if self.recording is not None and not self.recording_started:
            self.recording_started = True
            self.recording.add(self.frame(refresh=True), self.episode_time)

    def _check_live(self) -> None:
        if self.thread.error and not self._warned:
            self._warned = True
            print(f"viewer: {self.thread.error}; the session goes on without the live view", file=sys.stderr)

    # -- what is drawn besides the bodies -------------------------------------------------
    def _static_nodes(self) -> Frame:
        """The kitchen's semantic locations: their names, and a translucent region where no fixture shows it."""
        locations = getattr(getattr(self.world, "kitchen", None), "locations", None) or {}
        fixtures = getattr(getattr(self.world, "kitchen", None), "fixtures", None) or {}
        top = float(_counter_box(self.world)[1][2])
        nodes: Frame = {}
        for index, name in enumerate(sorted(locations)):
            location = locations[name]
            (cx, cy, cz), (hx, hy) = location.centre, location.half_size
            rgba = (*REGION_RGBA[index % len(REGION_RGBA)], 0.3)
            z = max(top, float(cz)) + 0.002
            if name not in fixtures:
                nodes[f"kitchen/locations/{name}"] = ((Look("box", (2 * hx, 2 * hy, 0.003), rgba),),
                                                     translation(cx, cy, z))
            nodes[f"kitchen/location-names/{name}"] = (self._label(name, "location", REGION_LABEL_HEIGHT_M,
                                                                   SCREEN_REGION_LABEL_HEIGHT),
                                                       translation(cx, cy + hy - 0.02, z + 0.02))
        return nodes

    def _label(self, text: str, style: str, metres: float, screen: float) -> tuple[Look, ...]:
        """A label in the scene (``metres`` tall), or in a page (no panels) one of a constant screen size."""
        return _text(text, style, metres) if self.panels else _text(text, style, screen, True)

    def _overlay(self) -> Frame:
        nodes: Frame = {}
        boxes = self.reader.object_boxes()
        for index, (node, (low, high)) in enumerate(zip(self.reader.object_nodes, boxes)):
            style = "label-asked" if index == self.asked else "label-shown" if index == self.shown else "label"
            centre = (low + high) / 2
            nodes[f"labels/{node.rsplit('/', 1)[-1]}"] = (self._label(str(index + 1), style, LABEL_HEIGHT_M,
                                                                      SCREEN_LABEL_HEIGHT),
                                                          translation(centre[0], centre[1], high[2] + 0.045))
        for name, index, rgba in (("asked", self.asked, ASKED_RGBA), ("shown", self.shown, SHOWN_RGBA)):
            if index is not None and 0 <= index < len(boxes):
                low, high = boxes[index]
                size = tuple(round(float(v), 3) for v in (high - low) + 0.03)
                nodes[f"overlay/{name}"] = ((Look("box", size, rgba),), translation(*((low + high) / 2)))
        top = self._text_anchor.copy()
        for name, text in (("question", self.question), ("answer", self.answer)) if self.panels else ():
            if text:  # sprites face the camera, so they stack along the camera's up direction
                text = _wrapped(text)
                height = TEXT_HEIGHT_M * (text.count("\n") + 1)
                centre = top - self._screen_up * height / 2
                nodes[f"overlay/{name}"] = (_text(text, "panel", height), translation(*centre))
                top = top - self._screen_up * (height + 0.012)
        return nodes

    # -- dialog observer ---------------------------------------------------------------
    def on_scene(self, scene=None) -> None:
        """A new scene: clear the dialog overlay, re-read the bodies, begin the recording if asked for."""
        self.question = self.answer = ""
        self.asked = self.shown = None
        if self.recording is not None and not self.recording_started:
            self.recording_started = True
        self.update(DWELL_S["scene"])

    def on_question(self, action, text=None, scene=None) -> None:
        """The robot asks: highlight the object of a label question, show the question."""
        if isinstance(action, dict) and not isinstance(text, str):
            text, action = action.get("question", ""), action.get("action", action)
        kind, index, _ = _action_fields(action)
        self.asked = index if kind == "label" else None
        self.shown = None
        self.question = f"Robot: {text}" if text else ""
        self.answer = "Teacher: …"
        self._asked_this_turn = True
        self.update(DWELL_S["question"])

    def on_answer(self, action, outcome=None, scene=None) -> None:
        """The teacher answers: show the answer; an object shown in a demonstration turns green."""
        kind, _, _ = _action_fields(action)
        raw = outcome.get("raw", "") if isinstance(outcome, dict) else getattr(outcome, "raw", outcome)
        value = outcome.get("value") if isinstance(outcome, dict) else getattr(outcome, "value", None)
        how = outcome.get("kind", "") if isinstance(outcome, dict) else getattr(outcome, "kind", "")
        self.answer = f"Teacher: {raw}" if raw else f"Teacher: ({how or 'no answer'})"
        if kind == "demo" and isinstance(value, (int, np.integer)) and not isinstance(value, bool):
            self.shown = int(value)
        self.update(DWELL_S["answer"])

    def on_turn(self, record=None, scene=None) -> None:
        """The turn is over; without question/answer events the record tells what was asked and answered."""
        if not self._asked_this_turn and isinstance(record, dict):
            kind, index, _ = _action_fields(record.get("action", {}))
            if kind in ("", "none"):
                self.question, self.answer, self.asked, self.shown = "Robot stays quiet.", "", None, None
                self.update(DWELL_S["quiet"])
            else:
                self.on_question(record.get("action", {}), record.get("question", ""), scene)
                self.on_answer(record.get("action", {}), record.get("answer", {}), scene)
        self._asked_this_turn = False

    def caption(self, text: str, detail: str = "", marked: int | None = None, dwell_s: float = 0.0) -> None:
        """Outside a dialog (a recipe's demonstrations and execution): show ``text`` and ``detail`` in the
        scene and mark object ``marked`` (0-based, the world's order) as the one the robot means."""
        self.question, self.answer = str(text), str(detail)
        self.asked, self.shown = marked, None
        self.update(dwell_s)

    # -- export and shutdown ----------------------------------------------------------
    def export_html(self, path: str | Path, title: str = "teachbot episode") -> dict:
        """Write everything recorded so far as one static HTML page (meshcat animation, no server)."""
        if self.recording is None or not self.recording.samples:
            raise ViewerError("nothing recorded: make the viewer with record=True and let a scene be shown")
        return self.thread.submit(lambda: export_html(self.recording, path, self.camera, title)).result()

    def close(self) -> dict | None:
        """Stop following the simulation, write the export if one was asked for, stop the server."""
        if self._closed:
            return None
        self._closed = True
        remove_step_listener(self.client, self._after_step)
        try:
            if self.export_path is not None and self.recording is not None and self.recording.samples:
                return self.export_html(self.export_path)
            return None
        finally:
            self.thread.stop()

    def __enter__(self) -> Viewer:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _unit_xy(vector: np.ndarray) -> np.ndarray:
    norm = float(np.hypot(vector[0], vector[1]))
    return np.array([vector[0] / norm, vector[1] / norm, 0.0]) if norm > 1e-9 else np.array([0.0, 1.0, 0.0])
