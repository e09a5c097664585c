"""The end-of-session summary lines that ``demo`` and ``teach`` print, in words."""

from __future__ import annotations

from dialog.clock import WallClock

# query kind: (one, many)
QUERY_WORDS = {"label": ("label", "labels"), "demo": ("demonstration", "demonstrations"),
               "feature": ("feature question", "feature questions"), "none": ("quiet turn", "quiet turns")}


def questions_in_words(queries: dict) -> str:
    """``{'label': 6, 'demo': 3, ...}`` -> "6 labels, 3 demonstrations, 1 feature question, 20 quiet turns"."""
    unknown = sorted(set(queries) - set(QUERY_WORDS))
    if unknown:
        raise ValueError(f"unknown query kinds {unknown}")
    parts = []
    for kind, (one, many) in QUERY_WORDS.items():
        count = int(queries.get(kind, 0))
        parts.append(f"{count} {one if count == 1 else many}")
    return ", ".join(parts)


def session_time(clock, run_seconds: float, resumed: list[dict]) -> str:
    """How long the session took, in words; a resumed one counts the recorded part too.

    With a wall clock (a person, or real time) the session clock went on from the transcript's last
    ``ended`` time, so its reading is the whole session's time. A scripted session's clock is virtual:
    its wall time is this run's, said so when earlier turns were replayed.
    """
    if not isinstance(clock, WallClock):
        return f"{run_seconds:.1f} s" + (f" in this run ({len(resumed)} recorded turns replayed)" if resumed else "")
    total = clock.now()
    if not resumed:
        return f"{total:.1f} s"
    before = float(resumed[-1].get("ended", resumed[-1].get("time", 0.0)))
    return f"{total:.1f} s in all ({before:.1f} s before the resume, {max(total - before, 0.0):.1f} s after)"


def scene_size(task) -> str:
    """"12 objects a scene (an interactive size; the thesis's experiments use 55)" for a task smaller than its
    largest scene, else "55 objects a scene"."""
    if task.objects_per_scene < task.max_objects_per_scene:
        return (f"{task.objects_per_scene} objects a scene (an interactive size; the thesis's experiments use "
                f"{task.max_objects_per_scene})")
    return f"{task.objects_per_scene} objects a scene"
