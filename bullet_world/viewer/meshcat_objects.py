"""Turning viewer looks into meshcat (three.js JSON) objects, and keeping a meshcat scene equal to a frame.

Only the viewer's meshcat thread uses this module. :class:`MeshcatScene`
sends a node's geometry when the node first appears or its looks change,
and afterwards only its transform, and only when it moved.
"""

from __future__ import annotations

import base64
import io
import uuid
from functools import lru_cache
from pathlib import Path

import numpy as np
import umsgpack
from meshcat.geometry import Object
from PIL import Image, ImageDraw, ImageFont

from bullet_world.viewer import meshes
from bullet_world.viewer.meshes import read_obj
from bullet_world.viewer.scene import Frame, Look, same_pose, translation

# text styles: (text colour, background rgba, font pixels)
TEXT_STYLES = {
    "panel": ((20, 20, 30), (255, 255, 255, 225), 36),
    "label": ((255, 255, 255), (40, 40, 48, 220), 56),
    "label-asked": ((0, 0, 0), (255, 214, 0, 255), 64),
    "label-shown": ((255, 255, 255), (20, 150, 60, 255), 64),
    "location": ((40, 40, 40), (255, 255, 255, 170), 40),
}
QUARTER_TURN_X = np.array([[1.0, 0, 0, 0], [0, 0, -1, 0], [0, 1, 0, 0], [0, 0, 0, 1]])  # three.js y axis -> z
MOVE_TOLERANCE = 1e-5


def _uuid() -> str:
    return str(uuid.uuid4())


def _hex(rgba) -> int:
    r, g, b = (int(round(255 * min(max(float(c), 0.0), 1.0))) for c in rgba[:3])
    return (r << 16) | (g << 8) | b


def _column_major(matrix: np.ndarray) -> list[float]:
    return [float(v) for v in np.asarray(matrix).ravel(order="F")]


@lru_cache(maxsize=8)
def _font(pixels: int):
    try:
        return ImageFont.load_default(size=pixels)
    except TypeError:  # Pillow without FreeType sizes
        return ImageFont.load_default()


@lru_cache(maxsize=512)
def text_image(text: str, style: str) -> tuple[bytes, float]:
    """A PNG of ``text`` (lines split at newlines) on a rounded panel, and its width / height."""
    ink, background, pixels = TEXT_STYLES.get(style, TEXT_STYLES["panel"])
    font = _font(pixels)
    left, top, right, bottom = ImageDraw.Draw(Image.new("RGBA", (1, 1))).textbbox((0, 0), text, font=font)
    pad = pixels // 3
    height = bottom - top + 2 * pad
    width = max(right - left + 2 * pad, height)
    image = Image.new("RGBA", (width, height), (0, 0, 0, 0))
    draw = ImageDraw.Draw(image)
    draw.rounded_rectangle((0, 0, width - 1, height - 1), radius=pad, fill=background)
    draw.text(((width - (right - left)) / 2 - left, pad - top), text, font=font, fill=(*ink, 255), align="center")
    buffer = io.BytesIO()
    image.save(buffer, format="PNG", compress_level=1)  # fast: a question is drawn while the episode runs
    return buffer.getvalue(), width / height


def _image_texture(data: bytes, json: dict, repeat: bool = False) -> str:
    image, texture = _uuid(), _uuid()
    json["images"].append({"uuid": image, "url": "data:image/png;base64," + base64.b64encode(data).decode("ascii")})
    wrap = 1000 if repeat else 1001  # RepeatWrapping, ClampToEdgeWrapping
    json["textures"].append({"uuid": texture, "image": image, "wrap": [wrap, wrap], "repeat": [1, 1],
                             "anisotropy": 4})
    return texture


@lru_cache(maxsize=64)
def _mesh_data(file: str):
    path = Path(file)
    if path.suffix.lower() == ".stl":
        return umsgpack.Ext(0x12, path.read_bytes())  # meshcat's extension code for a uint8 array
    return path.read_text(encoding="utf-8", errors="replace")


def _mesh_geometry(file: str, with_uvs: bool) -> dict:
    """OBJ files as binary triangle arrays (see :mod:`bullet_world.viewer.meshes`); STL and COLLADA as
    files for meshcat's loaders in the page."""
    kind = Path(file).suffix.lower().lstrip(".")
    if kind == "obj":
        return read_obj(file, with_uvs, meshes.VIEWER_TRIANGLES).geometry_json(_uuid())
    return {"uuid": _uuid(), "type": "_meshfile_geometry", "format": kind, "data": _mesh_data(file)}


def _geometries(look: Look) -> list[tuple[dict, np.ndarray]]:
    """three.js geometry JSON and its pose in the part for one look (a capsule needs three)."""
    if look.shape == "box":
        lx, ly, lz = look.size
        return [({"type": "BoxGeometry", "width": lx, "height": ly, "depth": lz}, np.eye(4))]
    if look.shape == "plane":
        return [({"type": "BoxGeometry", "width": look.size[0], "height": look.size[1], "depth": 0.001}, np.eye(4))]
    if look.shape == "sphere":
        return [({"type": "SphereGeometry", "radius": look.size[0], "widthSegments": 32, "heightSegments": 16},
                 np.eye(4))]
    if look.shape in ("cylinder", "capsule"):
        radius, length = look.size
        parts = [({"type": "CylinderGeometry", "radiusTop": radius, "radiusBottom": radius, "height": length,
                   "radialSegments": 48}, QUARTER_TURN_X)]
        if look.shape == "capsule":
            cap = {"type": "SphereGeometry", "radius": radius, "widthSegments": 24, "heightSegments": 12}
            parts += [(dict(cap), translation(0, 0, side * length / 2)) for side in (-1, 1)]
        return parts
    if look.shape == "mesh":
        return [(_mesh_geometry(look.file, bool(look.texture)), np.diag([*look.size, 1.0]))]
    raise ValueError(f"cannot draw a '{look.shape}'")


def _empty_json() -> dict:
    return {"metadata": {"version": 4.5, "type": "Object"}, "geometries": [], "materials": [], "textures": [],
            "images": []}


def _sprite_json(look: Look) -> dict:
    data, aspect = text_image(look.text, look.style)
    json = _empty_json()
    # "screen-text" keeps one size on the screen however far the camera is (a page's number labels: readable
    # beside the page's text); its height is then a share of the view (three.js multiplies it by the depth)
    material = {"uuid": _uuid(), "type": "SpriteMaterial", "color": 0xFFFFFF, "transparent": True,
                "depthTest": False, "depthWrite": False, "sizeAttenuation": look.shape != "screen-text",
                "map": _image_texture(data, json)}
    json["materials"].append(material)
    height = look.size[0]
    matrix = np.asarray(look.local, dtype=float).reshape(4, 4) @ np.diag([height * aspect, height, 1.0, 1.0])
    json["object"] = {"uuid": _uuid(), "type": "Sprite", "material": material["uuid"], "renderOrder": 10,
                      "matrix": _column_major(matrix)}
    return json


def object_jsons(look: Look) -> list[dict]:
    """The three.js object JSON documents (one per geometry) that draw ``look``."""
    if look.shape in ("text", "screen-text"):
        return [_sprite_json(look)]
    local = np.asarray(look.local, dtype=float).reshape(4, 4)
    result = []
    for geometry, placement in _geometries(look):
        json = _empty_json()
        geometry.setdefault("uuid", _uuid())
        json["geometries"].append(geometry)
        opacity = float(look.rgba[3])
        material = {"uuid": _uuid(), "type": "MeshPhongMaterial", "color": _hex(look.rgba), "side": 2,
                    "transparent": opacity < 1.0, "opacity": opacity, "depthWrite": opacity >= 1.0,
                    "shininess": 20}
        if look.texture and Path(look.texture).is_file():
            material["map"] = _image_texture(Path(look.texture).read_bytes(), json, repeat=True)
        json["materials"].append(material)
        json["object"] = {"uuid": _uuid(), "type": "Mesh", "geometry": geometry["uuid"],
                          "material": material["uuid"], "matrix": _column_major(local @ placement)}
        result.append(json)
    return result


class RawObject(Object):
    """A meshcat object whose three.js JSON is already built."""

    def __init__(self, json: dict):  # no geometry or material objects to keep
        self.json = json

    def lower(self):
        return self.json


class MeshcatScene:
    """Keeps the meshcat scene under ``root`` equal to the frames it is given."""

    def __init__(self, visualizer, root: str = "world"):
        self.vis = visualizer[root]
        self._looks: dict[str, tuple[Look, ...]] = {}
        self._poses: dict[str, np.ndarray] = {}
        self._built: dict[Look, list[dict]] = {}
        self.sent = {"objects": 0, "transforms": 0, "deletes": 0}

    def _jsons(self, look: Look) -> list[dict]:
        if look not in self._built:
            if len(self._built) > 2048:
                self._built.clear()
            self._built[look] = object_jsons(look)
        return self._built[look]

    def set_node(self, node: str, looks: tuple[Look, ...]) -> None:
        """Draw ``looks`` at ``node`` (its parts at ``node/p0``, ``node/p1``, ...)."""
        if node in self._looks:
            self.vis[node].delete()
            self.sent["deletes"] += 1
        index = 0
        for look in looks:
            for json in self._jsons(look):
                self.vis[node][f"p{index}"].set_object(RawObject(json))
                index += 1
                self.sent["objects"] += 1
        self._looks[node] = looks
        self._poses.pop(node, None)

    def set_pose(self, node: str, matrix: np.ndarray) -> None:
        previous = self._poses.get(node)
        if previous is not None and same_pose(previous, matrix, MOVE_TOLERANCE):
            return
        self.vis[node].set_transform(np.asarray(matrix, dtype=float))
        self._poses[node] = np.array(matrix, dtype=float)
        self.sent["transforms"] += 1

    def apply(self, frame: Frame) -> None:
        """Delete vanished nodes, (re)draw new or changed ones, move the rest."""
        for node in [n for n in self._looks if n not in frame]:
            self.vis[node].delete()
            del self._looks[node]
            self._poses.pop(node, None)
            self.sent["deletes"] += 1
        for node, (looks, matrix) in frame.items():
            if self._looks.get(node) != looks:
                self.set_node(node, looks)
            self.set_pose(node, matrix)
        self.flush()

    def flush(self) -> None:
        """Wait for the server to take every command sent (a pipelined window collects its replies)."""
        flush = getattr(getattr(self.vis, "window", None), "flush", None)
        if flush is not None:
            flush()


def set_camera(visualizer, eye, target) -> None:
    """Put meshcat's camera at ``eye`` orbiting ``target`` (world coordinates, z up)."""
    eye, target = np.asarray(eye, dtype=float), np.asarray(target, dtype=float)
    offset = eye - target
    visualizer["/Cameras/default"].set_transform(translation(*target))
    # the camera's parent turns three.js's y-up frame to z-up: world (x, y, z) is local (x, z, -y)
    visualizer["/Cameras/default/rotated/<object>"].set_property("position", [offset[0], offset[2], -offset[1]])
    visualizer["/Grid"].set_property("visible", False)
    visualizer["/Axes"].set_property("visible", False)
