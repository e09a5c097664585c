"""Scripted-teacher regression runs: suites of episodes, reports, baselines (``teachbot regress``)."""
