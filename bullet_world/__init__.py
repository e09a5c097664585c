"""The simulated kitchen: scenes, objects, camera, perception.

The world hands the learner plain data (a feature matrix per scene and the
feature names), never a simulator handle.
"""

from bullet_world.simulator import import_pybullet_quietly

import_pybullet_quietly()  # before any module below imports it: no banner on standard error

from bullet_world.scene import Scene  # noqa: E402
from bullet_world.world import World  # noqa: E402

__all__ = ["Scene", "World"]
