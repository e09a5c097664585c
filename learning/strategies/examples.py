"""A strategy written from scratch against the public API only, as docs/library.md's worked example.

It ships inside ``learning`` so that ``learning.strategies.examples:EveryOtherTurn`` imports wherever teachbot is
installed (any folder, any worker process); a strategy of your own lives in your own package on PYTHONPATH. It is
not registered: only the ``module.path:ClassName`` form runs it.
"""

import numpy as np

from learning import Decision, LabelQuery, LearningState, NoQuery, Strategy


class EveryOtherTurn(Strategy):
    """Label the object the learner is least sure of, but only every other turn (the teacher rests between)."""

    def choose(self, state: LearningState, rng: np.random.Generator) -> Decision:
        if not state.can_afford(LabelQuery(0)):
            return Decision(NoQuery(), "Nothing to ask: I can't afford a label query.")
        if state.turn % 2 == 1:
            return Decision(NoQuery(), "I let the teacher rest every other turn.")
        open_objects = [i for i in range(len(state.scene_X)) if i not in state.labelled_in_scene]
        if not open_objects:
            return Decision(NoQuery(), "Nothing to ask: I know every object in this scene.")
        sureness = state.probabilities().max(axis=1)  # p(best guess) of each scene object
        index = min(open_objects, key=lambda i: (sureness[i], i))
        return Decision(LabelQuery(index), f"I am least sure what object {index + 1} is "
                                           f"(my best guess has p = {sureness[index]:.2f}).")
