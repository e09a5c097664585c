"""What-if engines for the decision-theoretic learner: ``make_engine("fast" | "reference")``."""

from __future__ import annotations

from learning.whatif.base import Outcomes, WhatIfEngine, feature_query_subsets
from learning.whatif.fast import FastEngine
from learning.whatif.reference import ReferenceEngine

ENGINES: dict[str, type[WhatIfEngine]] = {"fast": FastEngine, "reference": ReferenceEngine}
ENGINE_NAMES = tuple(ENGINES)


def make_engine(engine: str | WhatIfEngine = "fast") -> WhatIfEngine:
    """An engine by name (or the engine itself); a clear error lists the accepted names."""
    if isinstance(engine, WhatIfEngine):
        return engine
    key = str(engine).strip().lower()
    if key not in ENGINES:
        raise ValueError(f"unknown what-if engine '{engine}'; choose one of: {', '.join(ENGINE_NAMES)}")
    return ENGINES[key]()


__all__ = ["ENGINE_NAMES", "FastEngine", "Outcomes", "ReferenceEngine", "WhatIfEngine", "feature_query_subsets",
           "make_engine"]
