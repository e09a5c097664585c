"""The rules of one turn, in one place (issue 25): what may be asked now and why not, and when the world changes.

``TeachingLoop`` (the library), ``DialogManager`` (demo, teach, regress, study, expert, the Gymnasium
environment) and the synthetic episodes of ``learning.synthetic`` all call these, so a strategy behaves
the same wherever it runs. Charging a question and advancing the clock are ``LearningState.apply``'s.
"""

from __future__ import annotations

from learning.actions import Action, NoQuery
from learning.state import LearningState


def admissible(state: LearningState, action: Action) -> tuple[Action, str]:
    """The action itself if it may be asked now, else no query and the reason (a sentence a person reads).

    In order: a query that does not fit the state (an unknown kind, an object not in the scene, an unknown
    concept; ``LearningState.check_action``); one the budget can't pay for; the feature query a second time.
    """
    if action.kind == "none":
        return action, ""
    try:
        state.check_action(action)
    except ValueError as error:
        return NoQuery(), f"Nothing to ask: {error}."
    if not state.can_afford(action):
        return NoQuery(), f"Nothing to ask: the budget is spent ({state.spent:g} of {state.budget:g})."
    if action.kind == "feature" and state.feature_query_asked:
        return NoQuery(), "Nothing to ask: I already asked which features matter."
    return action, ""


def scene_epoch(turns_finished: int, change_every: int) -> int:
    """The block of ``change_every`` turns the next turn falls in; the world changes when this grows."""
    return turns_finished // change_every


def scene_due(turns_finished: int, change_every: int, last_scene_epoch: int | None) -> bool:
    """True when the next turn needs a new scene: none seen yet (``last_scene_epoch`` None), or a new block of
    ``change_every`` turns has begun since the last one was observed."""
    return last_scene_epoch is None or scene_epoch(turns_finished, change_every) > last_scene_epoch


def budget_spent(state: LearningState) -> bool:
    """True when the remaining budget can pay for no question the learner may still ask: neither a label nor a
    demonstration query, nor the feature query if it has not been asked. The thesis's chapter-6 episodes end
    after the turn in which this becomes true (docs/experiments.md, "How a chapter-6 episode ends"); a kind
    that costs nothing is always affordable, so such a budget is never spent."""
    kinds = ("label", "demo") if state.feature_query_asked else ("label", "demo", "feature")
    return not any(state.progress.affords(state.costs[kind]) for kind in kinds)
