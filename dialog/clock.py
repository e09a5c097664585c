"""Session clocks: seconds since the session began. Injected, so that tests never sleep.

``VirtualClock`` only moves when told to (simulated motion time, a scripted
teacher's answer delay); ``WallClock`` follows the real monotonic clock and
really sleeps. Both can be started at an offset, so that a resumed session
goes on from the time its transcript ended.
"""

from __future__ import annotations

import time


class VirtualClock:
    """Time that passes only through ``sleep``/``advance`` (deterministic)."""

    def __init__(self, start: float = 0.0):
        self._now = float(start)

    def now(self) -> float:
        return self._now

    def sleep(self, seconds: float) -> None:
        if seconds > 0:
            self._now += float(seconds)

    advance = sleep

    def sleep_until(self, moment: float) -> None:
        self._now = max(self._now, float(moment))

    def set(self, moment: float) -> None:
        self._now = float(moment)


class WallClock:
    """Real time since construction (plus ``start``); ``sleep`` really waits.

    ``counts_simulated``: ``advance`` adds simulated time (the arm's motion, embodied costs) on top of the real
    time, so that a person's session with embodied costs counts both."""

    def __init__(self, start: float = 0.0, monotonic=time.monotonic, sleeper=time.sleep,
                 counts_simulated: bool = False):
        self._monotonic, self._sleeper = monotonic, sleeper
        self._origin = monotonic() - float(start)
        self.counts_simulated = counts_simulated

    def now(self) -> float:
        return self._monotonic() - self._origin

    def sleep(self, seconds: float) -> None:
        if seconds > 0:
            self._sleeper(seconds)

    def advance(self, seconds: float) -> None:
        """Simulated time (the arm's motion) does not move the wall clock, unless it ``counts_simulated``."""
        if self.counts_simulated and seconds > 0:
            self._origin -= float(seconds)

    def sleep_until(self, moment: float) -> None:
        self.sleep(moment - self.now())

    def set(self, moment: float) -> None:
        self._origin = self._monotonic() - float(moment)
