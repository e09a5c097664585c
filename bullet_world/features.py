"""The named, grouped feature catalogue and the per-object feature vector."""

from __future__ import annotations

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from bullet_world.catalogue import DATA_DIR, DataFileError
from bullet_world.perception import ObjectMeasurement


@dataclass(frozen=True)
class FeatureInfo:
    """A feature's stable name, its place in the hierarchy and a plain description."""

    name: str
    group: str
    description: str
    source: str = "object"  # "object": measured per object; "robot": from the attached robot


@lru_cache(maxsize=1)
def feature_catalogue() -> tuple[FeatureInfo, ...]:
    """Every feature of ``data/features.toml``, in column order."""
    path = DATA_DIR / "features.toml"
    with open(path, "rb") as handle:
        entries = tomllib.load(handle).get("feature", [])
    infos = []
    for index, entry in enumerate(entries):
        missing = [key for key in ("name", "group", "description") if not entry.get(key)]
        if missing:
            raise DataFileError(f"{path}: feature {index + 1} lacks {', '.join(missing)}")
        source = entry.get("source", "object")
        if source not in ("object", "robot"):
            raise DataFileError(f"{path}: feature '{entry['name']}' has source '{source}'; use object or robot")
        infos.append(FeatureInfo(entry["name"], entry["group"], entry["description"], source))
    names = [info.name for info in infos]
    if len(set(names)) != len(names):
        raise DataFileError(f"{path}: feature names must be unique")
    return tuple(infos)


def object_feature_catalogue() -> tuple[FeatureInfo, ...]:
    """The features measured per object, in column order."""
    return tuple(info for info in feature_catalogue() if info.source == "object")


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


def object_feature_values(measurement: ObjectMeasurement, weight_reading: float) -> dict[str, float]:
    """Feature values of one measured object, keyed by catalogue name."""
    red, green, blue = (float(c) for c in measurement.mean_rgb)
    x, y, z = (float(c) for c in measurement.centroid)
    return {
        "colour.red": red, "colour.green": green, "colour.blue": blue,
        "size.length": measurement.length, "size.width": measurement.width, "size.height": measurement.height,
        "location.x": x, "location.y": y, "location.z": z,
        "weight": float(weight_reading),
    }


def feature_row(values: dict[str, float], names: tuple[str, ...]) -> np.ndarray:
    """Order a name -> value mapping as a row of the feature matrix."""
    missing = [name for name in names if name not in values]
    if missing:
        raise KeyError(f"no value computed for features {missing}")
    return np.array([values[name] for name in names], dtype=np.float64)
