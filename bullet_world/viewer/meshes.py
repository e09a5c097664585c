"""Wavefront OBJ files as indexed triangle arrays for the viewer (three.js buffer geometry).

meshcat can parse OBJ text in the browser, but it fails on files whose
groups differ in their attributes (some of the Panda's links) and parsing
9 MB of text in the page is slow. Reading the file here once, with numpy,
gives compact binary arrays that every page and the exported HTML load as is.

A browser without a GPU (headless Chromium, many study laptops) draws in
software, where a frame costs about as much as its triangles: the Panda's links
hold 600-21,600 triangles each, about 100,000 in all. Meshes without texture
coordinates are simplified for the viewer to at most ``VIEWER_TRIANGLES``
triangles each by quadric edge collapse (Garland and Heckbert's quadric error
metric, through the fast-simplification package), which keeps the outline
within a millimetre or two (tests/bullet_world/test_viewer_mesh_simplify.py).
"""

from __future__ import annotations

import hashlib
import io
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np
import umsgpack
from meshcat.geometry import pack_numpy_array

from bullet_world.datafiles import cache_dir, write_atomically
from learning.errors import DataFileError

VIEWER_TRIANGLES = 3000  # the most triangles one mesh is drawn with in the viewer (see above)


class MeshFileError(DataFileError):
    """An OBJ file that can't be read as triangles."""


@dataclass(frozen=True)
class MeshArrays:
    """Triangles over unique corners: positions (n, 3), uvs (n, 2) or None, faces (m, 3) indices into
    the corners. Normals are left to the browser (smooth, from the triangles)."""

    positions: np.ndarray
    uvs: np.ndarray | None
    faces: np.ndarray

    def geometry_json(self, uuid: str) -> dict:
        """three.js BufferGeometry JSON with meshcat's packed typed arrays."""
        attributes = {"position": pack_numpy_array(self.positions.T)}
        if self.uvs is not None:
            attributes["uv"] = pack_numpy_array(self.uvs.T)
        if len(self.positions) < 2 ** 16:  # half the bytes: meshcat's msgpack reads extension 0x14 as Uint16Array
            index = {"itemSize": 3, "type": "Uint16Array", "normalized": False,
                     "array": umsgpack.Ext(0x14, self.faces.T.astype(np.uint16).tobytes("F"))}
        else:
            index = pack_numpy_array(self.faces.T)
        return {"uuid": uuid, "type": "BufferGeometry", "data": {"attributes": attributes, "index": index}}


def _numbers(lines: list[str], width: int, path: Path, what: str) -> np.ndarray:
    """The first ``width`` numbers of every line, as an (n, width) array (numpy parses the text)."""
    if not lines:
        return np.zeros((0, width))
    counts = {len(line.split()) for line in lines[:: max(1, len(lines) // 64)]}
    if counts == {width}:
        try:
            values = np.fromstring(" ".join(lines), sep=" ")
        except ValueError:  # something that is not a number: the line by line reading below names it
            values = np.zeros(0)
        if values.size == len(lines) * width:
            return values.reshape(-1, width)
    rows = [line.split()[:width] for line in lines]
    if any(len(row) != width for row in rows):
        raise MeshFileError(f"{path}: a '{what}' line holds fewer than {width} numbers")
    try:
        return np.array(rows, dtype=float).reshape(-1, width)
    except ValueError:
        raise MeshFileError(f"{path}: a '{what}' line holds something that is not a number") from None


def _corner_table(tokens: list[str]) -> np.ndarray:
    """(k, 3) array of 1-based (vertex, uv, normal) indices per face corner; 0 where absent."""
    joined = " ".join(tokens).replace("//", "/0/")
    fields = joined.split(" ", 1)[0].count("/") + 1
    if joined.count("/") == len(tokens) * (fields - 1):
        table = np.fromstring(joined.replace("/", " "), dtype=np.int64, sep=" ")
        if table.size == len(tokens) * fields:
            return np.pad(table.reshape(len(tokens), fields), ((0, 0), (0, 3 - fields)))
    table = np.zeros((len(tokens), 3), dtype=np.int64)  # mixed corner formats: one corner at a time
    for row, token in enumerate(tokens):
        parts = [int(part) if part else 0 for part in token.split("/")]
        table[row, :len(parts)] = parts[:3]
    return table


def _absolute(indices: np.ndarray, count: int) -> np.ndarray:
    """OBJ indices (1-based, negative counts from the end, 0 absent) as 0-based (-1 absent)."""
    return np.where(indices > 0, indices - 1, np.where(indices < 0, count + indices, -1))


def simplified(mesh: MeshArrays, triangles: int) -> MeshArrays:
    """The mesh with at most about ``triangles`` triangles, by quadric edge collapse; a mesh with texture
    coordinates, or already small enough, is returned as it is (a collapse would tear its texture mapping)."""
    if mesh.uvs is not None or len(mesh.faces) <= triangles:
        return mesh
    import fast_simplification

    points, faces = fast_simplification.simplify(mesh.positions.astype(np.float64), mesh.faces.astype(np.int32),
                                                 target_count=int(triangles))
    return MeshArrays(points.astype(np.float32), None, faces.astype(np.uint32))


@lru_cache(maxsize=64)
def read_obj(file: str, with_uvs: bool = False, max_triangles: int | None = None) -> MeshArrays:
    """An OBJ file's triangles (see :func:`parse_obj`), simplified to ``max_triangles`` when given and it has no
    uvs (:func:`simplified`), kept as NPZ in the teachbot cache folder so that later sessions skip the parsing
    (the Panda's visual meshes are 9 MB of text) and the simplification."""
    try:
        stat = Path(file).stat()
        key = hashlib.sha1(f"{Path(file).resolve()}|{stat.st_size}|{stat.st_mtime_ns}|{with_uvs}|{max_triangles}"
                           .encode())
        cached = cache_dir() / f"viewer-mesh-{key.hexdigest()[:20]}.npz"
    except OSError:
        mesh = parse_obj(file, with_uvs)
        return mesh if max_triangles is None else simplified(mesh, max_triangles)
    if cached.is_file():
        try:
            with np.load(cached, allow_pickle=False) as data:
                return MeshArrays(data["positions"], data["uvs"] if "uvs" in data else None, data["faces"])
        except (OSError, ValueError, KeyError):
            pass  # a damaged cache file is parsed again and replaced
    mesh = parse_obj(file, with_uvs)
    if max_triangles is not None:
        mesh = simplified(mesh, max_triangles)
    buffer = io.BytesIO()
    arrays = {"positions": mesh.positions, "faces": mesh.faces} | ({"uvs": mesh.uvs} if mesh.uvs is not None else {})
    np.savez(buffer, **arrays)
    try:
        write_atomically(cached, buffer.getvalue())
    except OSError:
        pass  # no cache, no harm
    return mesh


def parse_obj(file: str, with_uvs: bool = False) -> MeshArrays:
    """Read an OBJ file's triangles (polygons as fans); uvs when asked for and every corner has one."""
    path = Path(file)
    try:
        text = path.read_text(encoding="utf-8", errors="replace")
    except OSError as error:
        raise MeshFileError(f"{path}: cannot read ({error.strerror})") from None
    lines = text.splitlines()
    vertices = _numbers([line[2:] for line in lines if line.startswith("v ")], 3, path, "v")
    uv_table = _numbers([line[3:] for line in lines if line.startswith("vt ")], 2, path, "vt")
    polygons = [line.split()[1:] for line in lines if line.startswith("f ")]
    if len(vertices) == 0 or not polygons:
        raise MeshFileError(f"{path}: no vertices or no faces")
    sizes = np.array([len(polygon) for polygon in polygons])
    if sizes.min() < 3:
        raise MeshFileError(f"{path}: a face has fewer than 3 corners")
    try:
        corners = _corner_table([token for polygon in polygons for token in polygon])
    except ValueError:
        raise MeshFileError(f"{path}: a face corner is not 'v', 'v/vt', 'v//vn' or 'v/vt/vn'") from None
    corners = np.column_stack([_absolute(corners[:, 0], len(vertices)), _absolute(corners[:, 1], len(uv_table))])
    if corners[:, 0].min() < 0 or corners[:, 0].max() >= len(vertices):
        raise MeshFileError(f"{path}: a face refers to a vertex that does not exist")
    use_uvs = with_uvs and len(uv_table) > 0 and corners[:, 1].min() >= 0 and corners[:, 1].max() < len(uv_table)
    keys = corners[:, [0, 1]] if use_uvs else corners[:, :1]
    unique, corner_index = np.unique(keys, axis=0, return_inverse=True)
    corner_index = corner_index.ravel()
    triangles = []
    starts = np.concatenate([[0], np.cumsum(sizes)[:-1]])
    for size in np.unique(sizes):  # fan triangulation, one polygon size at a time
        first = starts[sizes == size]
        for k in range(1, size - 1):
            triangles.append(np.column_stack([first, first + k, first + k + 1]))
    faces = corner_index[np.vstack(triangles)].astype(np.uint32)
    uvs = uv_table[unique[:, 1]].astype(np.float32) if use_uvs else None
    return MeshArrays(vertices[unique[:, 0]].astype(np.float32), uvs, faces)
