"""Simulated non-visual sensors: the room microphone, the light sensor and the scale under the counter.

The thesis (§6.5.2) simulated these signals; here each has a seeded, explicit
noise model so the same seed gives the same readings.
"""

from __future__ import annotations

import numpy as np

from bullet_world.camera import Lighting

WEIGHT_NOISE_KG = 0.005        # standard deviation of the scale reading
LIGHT_NOISE = 0.02             # relative noise of the light sensor
SECONDS_BETWEEN_LOOKS = (5.0, 30.0)  # simulated time between two observations of the room
LEVEL_STEP_DB = 1.5            # background level random walk per observation
NOISE_WINDOW = 8               # noise features summarise this many most recent readings


class AmbientNoise:
    """The room's sound level in decibels: a background that drifts within the kitchen's range, plus
    short loud events (a kettle, the dishwasher) arriving as a Poisson process. Features summarise the
    lesson's recent readings (the last ``NOISE_WINDOW`` observations, a few minutes): loudest, quietest,
    average. A window rather than the whole lesson keeps the features' spread the same early and late in
    a lesson."""

    def __init__(self, config: dict, rng: np.random.Generator):
        self.config, self.rng = config, rng
        low, high = config["level_db"]
        self.level = float(rng.uniform(low, high))
        self.readings: list[float] = []

    def listen(self) -> float:
        """Advance the room by one interval between observations and take one reading."""
        low, high = self.config["level_db"]
        self.level = float(np.clip(self.level + self.rng.normal(0.0, LEVEL_STEP_DB), low, high))
        seconds = self.rng.uniform(*SECONDS_BETWEEN_LOOKS)
        events = self.rng.poisson(self.config["events_per_minute"] * seconds / 60.0)
        reading = self.level + self.rng.normal(0.0, 0.5)
        if events:
            reading = max(reading, float(self.rng.uniform(*self.config["event_db"])))
        self.readings.append(reading)
        return reading

    def summary(self) -> dict[str, float]:
        if not self.readings:
            self.listen()
        values = np.asarray(self.readings[-NOISE_WINDOW:])
        return {"noise.max": float(values.max()), "noise.min": float(values.min()), "noise.mean": float(values.mean())}

    def restart(self) -> None:
        """A new lesson: forget the readings (the room itself carries on)."""
        self.readings = []


def light_reading(lighting: Lighting, rng: np.random.Generator | None) -> dict[str, float]:
    """Level (brightness on the counter) and warmth (red minus blue of the light), with sensor noise
    unless ``rng`` is None."""
    colour = np.asarray(lighting.colour)
    noise = (0.0, 0.0) if rng is None else rng.normal(0.0, LIGHT_NOISE, 2)
    level = lighting.plane_shade() * float(colour.mean()) * (1.0 + noise[0])
    warmth = float(colour[0] - colour[2]) + noise[1] / 2
    return {"light.level": float(level), "light.warmth": float(warmth)}


def weigh(mass: float, rng: np.random.Generator) -> float:
    """The scale's reading of an object of ``mass`` kilograms."""
    return float(mass + rng.normal(0.0, WEIGHT_NOISE_KG))
