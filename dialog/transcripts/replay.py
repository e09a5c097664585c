"""Resuming a session: re-apply each recorded turn into a fresh episode and check that it repeats.

Nobody is asked: the recorded answer is applied to the rebuilt scene, and every
field the rebuilt episode can reproduce (the scene, the arm's gesture, the
question, the budget, the examples per concept) is compared with the record. A
record that does not repeat raises a :class:`TranscriptError` naming the turn.
"""

from __future__ import annotations

from dialog.teachers.protocol import FastForwards
from dialog.transcripts import records as checks
from dialog.transcripts.records import action_from_record, outcome_from_record
from learning.errors import TranscriptError


def replay_turn(manager, record: dict) -> None:
    """Re-apply one recorded turn (same scene, gesture, question, answer; nobody is asked) and check it.

    A record that the rebuilt episode does not reproduce raises a TranscriptError naming the turn.
    """
    number = manager.turn + 1
    turn, scene_id = record.get("turn"), record.get("scene_id")
    if not isinstance(turn, int) or isinstance(turn, bool) or turn != number:
        raise TranscriptError(f"transcript turn records are out of order: expected turn {number}, got {turn!r}")
    if not isinstance(scene_id, int) or isinstance(scene_id, bool):
        raise TranscriptError(f"turn {number}: 'scene_id' is {scene_id!r} (expected a whole number)")
    manager._start_turn(recorded_scene=scene_id)
    differs = checks.scene_difference(record.get("scene_check"), manager.scene)
    if manager.scene.scene_id != scene_id or differs:
        raise TranscriptError(f"turn {number} was recorded in another scene than the replay's ("
                              f"{differs or f'scene {scene_id} recorded, {manager.scene.scene_id} rebuilt'}): the "
                              "transcript was made with another seed, task or kitchen")
    decision = manager.strategy.choose(manager.state, manager.rngs["strategy"])  # keeps the strategy's stream in step
    try:
        action = action_from_record(record.get("action"))
        outcome = outcome_from_record(record, action, manager.state.feature_names)
    except ValueError as error:
        raise TranscriptError(f"turn {number}: {error}") from None
    problem = checks.scene_range_problem(action, outcome, manager.scene)
    if not problem and not manager.state.can_afford(action):
        problem = f"the {action.kind} query costs more than the {manager.state.remaining_budget:g} left of the budget"
    if not problem and "scene_check" not in record and "question" in record:  # older records: compare the text
        problem = checks.question_difference(record["question"], action, manager.questioner.describer(manager.scene),
                                             manager.state.concepts)
    if not problem and action.kind == "label":
        gesture = manager.env.point_at(manager.scene, action.object_index)
        manager.note_pointed(action.object_index)  # the arm now points there, as it did in the session
        problem = checks.gesture_difference(record.get("gesture"), gesture)
        problem = problem and f"the arm's gesture did not repeat ({problem}): the arm or the scene changed"
    if problem:
        raise TranscriptError(f"turn {number}: {problem}")
    if decision.action != action:
        manager.replay_mismatches += 1
    if action.kind != "none" and isinstance(manager.teacher, FastForwards):
        prompt = manager.prompt_for(action, decision.explanation, number, float(record.get("time", 0)), False)
        manager.teacher.fast_forward(prompt)
    undid = record.get("undid", [])
    if len(undid) > len(manager._undo_stack) or [manager._undo() for _ in undid] != undid:
        raise TranscriptError(f"turn {number}: 'undid' is {undid} (expected the latest learned turns, newest "
                              "first)")
    extra = manager._apply(action, outcome, manager.scene, replaying=True)  # learns and records the turn
    if "fetched" in record and extra.get("fetched", {}).get("kind") != record["fetched"].get("kind"):
        raise TranscriptError(f"turn {number}: the pantry fetch did not repeat ({extra.get('fetched')} instead of "
                              f"{record['fetched']})")
    differs = checks.model_difference(record, manager.model_summary(), manager.state.remaining_budget)
    if differs:
        raise TranscriptError(f"turn {number}: {differs}")
    if "ended" in record:
        manager.clock.set(float(record["ended"]))
    manager.turn += 1
    manager._notify("on_turn", record, manager.scene)
