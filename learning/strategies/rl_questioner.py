"""A trained reinforcement-learning questioner as a strategy: ``--strategy rl:FILE`` (beyond the thesis, ch. 8).

Each turn it encodes the learning state as the training environment did
(learning/rl/observation.py: phi(s), every slot's E[phi(s') | a] from the fast
what-if engine, the mask of candidates), runs the policy's forward pass
(learning/rl/policy_file.py, numpy only) and takes the allowed slot with the
highest logit: the deterministic policy, as ``teachbot regress`` compares it.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from learning.actions import Decision
from learning.rl.policy_file import QuestionerPolicy, load_policy, policy_digest
from learning.state import LearningState
from learning.strategies.base import Strategy
from learning.whatif import make_engine

PREFIX = "rl:"


class RLQuestionerStrategy(Strategy):
    """The deterministic action of a trained questioner policy; ``name`` is how reports show it."""

    def __init__(self, policy: QuestionerPolicy | str | Path, name: str | None = None, engine="fast"):
        self.file: str | None = None
        if not isinstance(policy, QuestionerPolicy):
            name = name or f"{PREFIX}{policy}"
            self.file = str(Path(policy).resolve())
            policy = load_policy(policy)
        self.policy = policy
        self.name = name or "rl"
        self.engine = make_engine(engine)

    def header_fields(self) -> dict:
        """What a transcript header records of the policy: its file and SHA-256 (a resume checks they still match)."""
        if self.file is None:
            return {}
        return {"policy": {"file": self.file, "sha256": policy_digest(self.file)}}

    def choose(self, state: LearningState, rng: np.random.Generator) -> Decision:
        observation = self.policy.layout.encode(state, self.engine)
        if observation.mask.sum() == 1:  # only no query is left
            return self.nothing_affordable(state)
        logits = self.policy.masked_logits(observation.vector, observation.mask)
        slot = int(np.argmax(logits))  # the allowed slot with the highest logit, ties to no query
        action = observation.actions[slot]
        assert action is not None, "the best slot is always an allowed one"
        margin = float(logits[slot] - np.sort(logits)[-2])  # at least two slots are open here
        if action.kind == "none":
            return Decision(action, f"Nothing to ask: my trained policy prefers to stay quiet now (logit margin "
                                    f"{margin:.2f} over its best question).")
        what = {"label": f"what object {getattr(action, 'object_index', 0) + 1} is",
                "demo": f"for a demonstration of {getattr(action, 'concept', '')}",
                "feature": "which features matter"}[action.kind]
        return Decision(action, f"My trained policy asks {what} (logit margin {margin:.2f} over the next choice).")
