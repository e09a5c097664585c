"""The simulated kitchen: scenes, objects, camera, perception.

The world hands the learner plain data (a feature matrix per scene and the
feature names), never a simulator handle.
"""

from bullet_world.scene import Scene
from bullet_world.world import World

__all__ = ["Scene", "World"]
