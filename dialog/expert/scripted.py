"""The scripted expert as a chooser for expert mode (`teachbot expert --expert scripted`, make_expert_demos.py).

The rules live in one place, ``learning.strategies.scripted_expert`` (the strategy
``scripted-expert``; its numbers in learning/strategies/data/scripted-expert.toml); this
chooser hands them the view ``dialog.expert.episode.ExpertStrategy`` builds, so an expert-mode episode
and a ``scripted-expert`` episode with the same seed ask the same questions.
"""

from __future__ import annotations

from dialog.expert.episode import ExpertView
from learning.actions import Action
from learning.strategies.scripted_expert import RULES_FILE, ExpertPlan, ExpertRules, paced_budget

__all__ = ["RULES_FILE", "ExpertRules", "ScriptedExpertChooser", "paced_budget"]


class ScriptedExpertChooser:
    """``ExpertPlan``'s choice for every turn; one instance per episode (the plan draws its feature-query turn once)."""

    name = "scripted-expert"

    def __init__(self, rules: ExpertRules | None = None):
        self.plan = ExpertPlan(rules)

    @property
    def rules(self) -> ExpertRules:
        return self.plan.rules

    def choose(self, view: ExpertView) -> Action:
        return self.plan.choose(view.turn, view.state, view.candidates, view.rng)[0]
