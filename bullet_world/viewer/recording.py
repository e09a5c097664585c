"""An episode recorded for meshcat's animation, and its export as one static HTML file.

The recording keeps, for every node, its *versions*: one per stretch of time
in which the node looked the same (an object of one scene, one question's
text). A version has a start, an end and pose keyframes, stored only when the
pose changed (plus the last unchanged pose before a change, so holds stay
still instead of drifting). Time is *episode time*: simulated seconds while
the simulation steps, plus a short pause at each dialog event so that
questions and answers can be read when the episode is played back.

The export builds the whole episode in a fresh loopback meshcat server:
every version's geometry once, its pose and visibility as animation tracks,
and asks the server for its static HTML, which opens with no server. The page
opens showing the episode's last frame (the last question, its highlight, the
arm at rest), so a plain screenshot of it shows how the episode ended; meshcat's
Animations > default > play plays it from the start.
"""

from __future__ import annotations

from contextlib import suppress
from dataclasses import dataclass, field
from pathlib import Path

import meshcat
import numpy as np
import umsgpack

from bullet_world.viewer.meshcat_objects import MOVE_TOLERANCE, RawObject, object_jsons, set_camera
from bullet_world.viewer.scene import Frame, Look, same_pose
from bullet_world.viewer.server import LocalServer, QuietWindow
from learning.errors import SettingsError


@dataclass
class Version:
    """One node looking one way from frame ``start`` until ``end`` (None: until the end)."""

    node: str
    looks: tuple[Look, ...]
    start: int
    end: int | None = None
    keys: list[tuple[int, np.ndarray]] = field(default_factory=list)
    last_seen: int = 0

    def key(self, frame: int, matrix: np.ndarray) -> None:
        """Note the pose at ``frame``; keyframes only where it changes."""
        if self.keys and (self.keys[-1][1] is matrix or same_pose(self.keys[-1][1], matrix, MOVE_TOLERANCE)):
            self.last_seen = frame
            return
        if self.keys and self.last_seen > self.keys[-1][0]:
            self.keys.append((self.last_seen, self.keys[-1][1]))  # hold still until the change
        if len(self.keys) >= 2 and self.keys[-1][0] == frame == self.keys[-2][0]:
            self.keys.pop()  # a second change within one frame replaces the first (a jump stays a jump)
        self.keys.append((frame, matrix))  # frames never change their matrices in place
        self.last_seen = frame


class Recording:
    """Frames at episode times, kept as node versions (see the module doc)."""

    def __init__(self, fps: int = 30):
        if fps < 1:
            raise SettingsError(f"the recording's frame rate must be at least 1 per second, got {fps}")
        self.fps = fps
        self.versions: list[Version] = []
        self._open: dict[str, Version] = {}
        self.last_frame = 0
        self.samples = 0

    def add(self, frame: Frame, time_s: float) -> None:
        number = max(int(round(time_s * self.fps)), self.last_frame)
        for node in [n for n in self._open if n not in frame]:
            self._open.pop(node).end = number
        for node, (looks, matrix) in frame.items():
            version = self._open.get(node)
            if version is None or version.looks != looks:
                if version is not None:
                    version.end = number
                version = Version(node, looks, number)
                self._open[node] = version
                self.versions.append(version)
            version.key(number, matrix)
        self.last_frame = number
        self.samples += 1

    @property
    def seconds(self) -> float:
        return self.last_frame / self.fps

    def shown(self) -> list[Version]:
        """The versions that were visible for at least one frame."""
        return [v for v in self.versions if v.end is None or v.end > v.start]


def export_html(recording: Recording, path: str | Path, camera: tuple, title: str = "teachbot episode",
                autoplay: bool = False) -> dict:
    """Write the recording as a self-contained HTML page with meshcat's animation controls.

    Every node's static state is its last one, so the page opens at the episode's end;
    ``autoplay`` starts the animation from the beginning as soon as the page loads instead.

    Must run on the viewer's meshcat thread (it talks to its own, temporary server).
    Returns the file's path, size, duration and counts.
    """
    path = Path(path)
    server = LocalServer()
    window = QuietWindow(server.zmq_url, server.web_url)
    try:
        vis = meshcat.Visualizer(window=window)
        set_camera(vis, *camera)
        root = vis["world"]
        animation = PackedAnimation(root.path, recording.fps)
        groups: dict[tuple, list[Version]] = {}
        for version in recording.shown():  # one exported node per node and look: geometry sent once
            groups.setdefault((version.node, version.looks), []).append(version)
        counts: dict[str, int] = {}
        for (node, looks), versions in groups.items():
            counts[node] = counts.get(node, 0) + 1
            _add_node(root, animation, f"{node}/v{counts[node] - 1}", looks, versions)
        vis.set_animation(animation, play=autoplay, repetitions=1)
        html = vis.static_html().replace("<title>MeshCat</title>", f"<title>{_escape(title)}</title>", 1)
    finally:
        window.close()
        server.stop()
    path.parent.mkdir(parents=True, exist_ok=True)
    try:
        path.write_text(html, encoding="utf-8")
    except OSError:  # a full disk: leave no half page behind, and let the caller name the cause
        with suppress(OSError):
            path.unlink(missing_ok=True)
        raise
    return {"path": str(path), "bytes": path.stat().st_size, "seconds": round(recording.seconds, 2),
            "nodes": len(groups)}


def _add_node(root, animation: PackedAnimation, name: str, looks: tuple[Look, ...], versions: list[Version]) -> None:
    """Geometry once, the last pose and visibility (what the page shows before it plays), and tracks
    for the pose and the visibility over all ``versions``."""
    node = root[name]
    index = 0
    for look in looks:
        for json in object_jsons(look):
            node[f"p{index}"].set_object(RawObject(json))
            index += 1
    visible = {0: False}
    keys: list[tuple[int, np.ndarray]] = []
    for version in versions:
        visible[version.start] = True
        keys.extend(version.keys)
        if version.end is not None:
            visible[version.end] = False
            if version.end > keys[-1][0]:
                keys.append((version.end, keys[-1][1]))  # hold until hidden: no drift towards the next stretch
    times = sorted(visible)
    node.set_transform(keys[-1][1])
    if not visible[times[-1]]:
        node.set_property("visible", False)
    tracks = [{"name": ".visible", "type": "boolean", "times": [float(t) for t in times],
               "values": [bool(visible[t]) for t in times]}]
    if any(not same_pose(keys[0][1], matrix, MOVE_TOLERANCE) for _, matrix in keys[1:]):
        frames = np.array([number for number, _ in keys], dtype=np.float32)
        matrices = np.array([matrix for _, matrix in keys])
        tracks += [{"name": ".position", "type": "vector3", "times": _floats(frames),
                    "values": _floats(matrices[:, :3, 3].ravel())},
                   {"name": ".quaternion", "type": "quaternion", "times": _floats(frames),
                    "values": _floats(quaternions_xyzw(matrices[:, :3, :3]).ravel())}]
    animation.clips.append((name, tracks))


class PackedAnimation:
    """meshcat's animation command, with every track's times and values as packed float32 arrays
    (three.js reads ``times``/``values``), so a long episode packs and loads quickly."""

    def __init__(self, root_path, fps: int):
        self.root_path, self.fps = root_path, fps
        self.clips: list[tuple[str, list[dict]]] = []

    def lower(self) -> list[dict]:
        return [{"path": self.root_path.append(name).lower(),
                 "clip": {"fps": self.fps, "name": "default", "tracks": tracks}} for name, tracks in self.clips]


def _floats(values: np.ndarray) -> umsgpack.Ext:
    """A Float32Array for meshcat's msgpack decoder (extension 0x17)."""
    return umsgpack.Ext(0x17, np.ascontiguousarray(values, dtype=np.float32).tobytes())


def quaternions_xyzw(rotations: np.ndarray) -> np.ndarray:
    """Unit quaternions (x, y, z, w) of (n, 3, 3) rotation matrices, w >= 0, continuous for interpolation."""
    m = rotations
    trace = m[:, 0, 0] + m[:, 1, 1] + m[:, 2, 2]
    candidates = np.stack([  # 4 * each component squared, pick the largest for a stable division
        1 + trace, 1 + m[:, 0, 0] - m[:, 1, 1] - m[:, 2, 2], 1 - m[:, 0, 0] + m[:, 1, 1] - m[:, 2, 2],
        1 - m[:, 0, 0] - m[:, 1, 1] + m[:, 2, 2]], axis=1)
    best = np.argmax(candidates, axis=1)
    q = np.zeros((len(m), 4))  # w, x, y, z
    for case in range(4):
        rows = best == case
        r = m[rows]
        s = 2.0 * np.sqrt(np.maximum(candidates[rows, case], 1e-12))
        if case == 0:
            q[rows] = np.column_stack([s / 4, (r[:, 2, 1] - r[:, 1, 2]) / s, (r[:, 0, 2] - r[:, 2, 0]) / s,
                                       (r[:, 1, 0] - r[:, 0, 1]) / s])
        elif case == 1:
            q[rows] = np.column_stack([(r[:, 2, 1] - r[:, 1, 2]) / s, s / 4, (r[:, 0, 1] + r[:, 1, 0]) / s,
                                       (r[:, 0, 2] + r[:, 2, 0]) / s])
        elif case == 2:
            q[rows] = np.column_stack([(r[:, 0, 2] - r[:, 2, 0]) / s, (r[:, 0, 1] + r[:, 1, 0]) / s, s / 4,
                                       (r[:, 1, 2] + r[:, 2, 1]) / s])
        else:
            q[rows] = np.column_stack([(r[:, 1, 0] - r[:, 0, 1]) / s, (r[:, 0, 2] + r[:, 2, 0]) / s,
                                       (r[:, 1, 2] + r[:, 2, 1]) / s, s / 4])
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    for i in range(1, len(q)):  # neighbouring keys in the same hemisphere: slerp takes the short way
        if np.dot(q[i], q[i - 1]) < 0:
            q[i] = -q[i]
    return q[:, [1, 2, 3, 0]]


def _escape(text: str) -> str:
    return text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")
