"""The named, grouped feature catalogue (thesis Table 5.1, §6.5.2) and the per-object feature values.

``data/features.toml`` names every feature, places it in the hierarchy the
teacher sees (``object/appearance/colour``) and describes it in plain words.
Object features come from the camera (:mod:`bullet_world.perception`), the
kitchen's interest points and the scale; environment features from the
microphone and the light sensor; robot features from the attached robot.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from bullet_world.datafiles import DATA_DIR, DataFileError, read_toml
from bullet_world.kitchen import INTEREST_POINTS, Kitchen
from bullet_world.perception import ObjectMeasurement
from learning.datafiles import check_keys, tables, text

SOURCES = ("object", "environment", "robot")
CROWDING_RADIUS_M = 0.20


@dataclass(frozen=True)
class FeatureInfo:
    """A feature's stable name, its place in the hierarchy and a plain description."""

    name: str
    group: str
    description: str
    source: str = "object"  # "object": per object; "environment": the room; "robot": the attached robot


@lru_cache(maxsize=1)
def feature_catalogue() -> tuple[FeatureInfo, ...]:
    """Every feature of ``data/features.toml``, in file order."""
    return load_feature_catalogue(DATA_DIR / "features.toml")


def load_feature_catalogue(path) -> tuple[FeatureInfo, ...]:
    """Read and check a feature catalogue file (``[[feature]]`` tables of name, group, description, source)."""
    table = read_toml(path, "features")
    check_keys(table, str(path), required=("feature",))
    infos = []
    for index, entry in enumerate(tables(table, "feature", str(path), nonempty=True)):
        where = f"{path}: feature {index + 1}"
        check_keys(entry, where, required=("name", "group", "description"), optional=("source",))
        infos.append(FeatureInfo(text(entry, "name", where), text(entry, "group", where),
                                 text(entry, "description", where), text(entry, "source", where, "object",
                                                                         choices=SOURCES)))
    names = [info.name for info in infos]
    if len(set(names)) != len(names):
        raise DataFileError(f"{path}: feature names must be unique")
    return tuple(infos)


def object_feature_catalogue() -> tuple[FeatureInfo, ...]:
    """The features measured per object, in column order."""
    return tuple(info for info in feature_catalogue() if info.source == "object")


def environment_feature_catalogue() -> tuple[FeatureInfo, ...]:
    """The room's features (the same for every object of an observation), in column order."""
    return tuple(info for info in feature_catalogue() if info.source == "environment")


def robot_feature_catalogue() -> tuple[FeatureInfo, ...]:
    """The features an attached robot reports, in column order."""
    return tuple(info for info in feature_catalogue() if info.source == "robot")


def feature_info(names) -> list[FeatureInfo]:
    """Name, group and description of each named feature (for the feature-subset question)."""
    by_name = {info.name: info for info in feature_catalogue()}
    unknown = [name for name in names if name not in by_name]
    if unknown:
        raise KeyError(f"features not in the catalogue: {unknown}")
    return [by_name[name] for name in names]


def resolve_feature_patterns(patterns, where: str = "relevant_features") -> tuple[str, ...]:
    """Feature names matched by each entry: a feature name, a group ("object/appearance") or a group's
    prefix, or a name prefix ("colour"); in catalogue order, each once."""
    catalogue = feature_catalogue()
    chosen: set[str] = set()
    for pattern in patterns:
        matches = {info.name for info in catalogue
                   if pattern in (info.name, info.group) or info.group.startswith(pattern + "/")
                   or info.name.startswith(pattern + ".")}
        if not matches:
            groups = sorted({info.group.split("/")[0] + "/" + info.group.split("/")[1] for info in catalogue})
            raise DataFileError(f"{where}: '{pattern}' names no feature; use feature names or groups such as "
                                f"{', '.join(groups)}")
        chosen |= matches
    return tuple(info.name for info in catalogue if info.name in chosen)


def object_feature_columns(measurements: list[ObjectMeasurement], weights, kitchen: Kitchen | None = None,
                           neighbours: bool = True) -> dict[str, np.ndarray]:
    """Feature values of measured objects, one array (n,) per catalogue name, all objects at once.

    ``kitchen`` gives the interest points, robot base and counter edges; ``neighbours`` adds the
    distance to the nearest other object and the crowding (both need the other objects in view).
    Without them those features are left out.
    """
    n = len(measurements)
    rgb = np.array([m.mean_rgb for m in measurements], dtype=float).reshape(n, 3)
    hsv = np.array([m.hsv for m in measurements], dtype=float).reshape(n, 3)
    centre = np.array([m.centroid for m in measurements], dtype=float).reshape(n, 3)

    def column(attribute: str) -> np.ndarray:
        return np.array([float(getattr(m, attribute)) for m in measurements])

    length, width, height = column("length"), column("width"), column("height")
    top_area, perimeter, volume = column("top_area"), column("perimeter"), column("volume")
    keypoints = column("keypoints")
    box_volume = length * width * height
    safe_volume = np.maximum(box_volume, 1e-9)
    values = {
        "colour.red": rgb[:, 0], "colour.green": rgb[:, 1], "colour.blue": rgb[:, 2],
        "colour.hue": hsv[:, 0], "colour.saturation": hsv[:, 1], "colour.value": hsv[:, 2],
        "colour.variation": column("variation"), "colour.contrast": column("contrast"),
        "texture.keypoints": keypoints, "texture.keypoint_density": keypoints / np.maximum(top_area * 1e4, 1e-3),
        "texture.edge_density": column("edge_density"),
        "size.length": length, "size.width": width, "size.height": height,
        "shape.box_area": length * width, "shape.footprint_area": top_area,
        "shape.box_volume": box_volume, "shape.volume": volume,
        "shape.aspect_ratio": length / np.maximum(width, 1e-4), "shape.tallness": height / np.maximum(length, 1e-4),
        "shape.surface_to_volume": 2 * (length * width + length * height + width * height) / safe_volume,
        "shape.compactness": np.minimum(volume / safe_volume, 1.5),
        "shape.roundness": 4 * np.pi * top_area / np.maximum(perimeter, 1e-6) ** 2,
        "shape.top_drop": column("top_drop"),
        "pose.yaw": column("yaw"),
        "location.x": centre[:, 0], "location.y": centre[:, 1], "location.z": centre[:, 2],
        "weight": np.asarray(weights, dtype=float).reshape(n),
    }
    xy = centre[:, :2]
    if kitchen is not None:
        for name in INTEREST_POINTS:
            origin = kitchen.locations[name].centre
            dx, dy = xy[:, 0] - origin[0], xy[:, 1] - origin[1]
            values |= {f"location.{name}.dx": dx, f"location.{name}.dy": dy,
                       f"location.{name}.distance": np.hypot(dx, dy)}
        local = kitchen.robot_frame(xy) if n else np.zeros((0, 2))
        values |= {"location.robot.forward": local[:, 0], "location.robot.left": local[:, 1],
                   "location.robot.distance": np.hypot(local[:, 0], local[:, 1]),
                   "location.robot.bearing": np.arctan2(local[:, 1], local[:, 0]),
                   "location.edge_distance": kitchen.counter_edge_distance(xy) if n else np.zeros(0)}
    if neighbours:
        distances = np.hypot(xy[:, None, 0] - xy[None, :, 0], xy[:, None, 1] - xy[None, :, 1])
        np.fill_diagonal(distances, np.inf)
        values["location.nearest_neighbour"] = distances.min(axis=1) if n > 1 else np.ones(n)  # alone: 1 m
        values["location.crowding"] = np.sum(distances <= CROWDING_RADIUS_M, axis=1).astype(float)
    return values


def object_feature_values(measurement: ObjectMeasurement, weight_reading: float, kitchen: Kitchen | None = None,
                          others_xy: np.ndarray | None = None) -> dict[str, float]:
    """Feature values of one measured object, keyed by catalogue name (``others_xy`` (m, 2): the centres
    of the other objects in view, for the neighbourhood features)."""
    others = [] if others_xy is None else [ObjectMeasurement(-1, 0, np.zeros(3), 0, 0, 0, np.r_[xy[:2], 0.0], 0, 0)
                                           for xy in np.asarray(others_xy, dtype=float).reshape(-1, 2)]
    columns = object_feature_columns([measurement, *others], [weight_reading] + [0.0] * len(others), kitchen,
                                     neighbours=others_xy is not None)
    return {name: float(values[0]) for name, values in columns.items()}


def feature_matrix(columns: dict[str, np.ndarray], shared: dict[str, float], names: tuple[str, ...],
                   n: int) -> np.ndarray:
    """(n, |names|) matrix from per-object columns and values shared by every object (room, robot)."""
    missing = [name for name in names if name not in columns and name not in shared]
    if missing:
        raise KeyError(f"no value computed for features {missing}")
    return np.column_stack([columns[name] if name in columns else np.full(n, float(shared[name]))
                            for name in names]) if names else np.zeros((n, 0))


def feature_row(values: dict[str, float], names: tuple[str, ...]) -> np.ndarray:
    """Order a name -> value mapping as a row of the feature matrix."""
    missing = [name for name in names if name not in values]
    if missing:
        raise KeyError(f"no value computed for features {missing}")
    return np.array([values[name] for name in names], dtype=np.float64)
