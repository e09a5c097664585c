"""Pure learning: concept models, query strategies, evaluation.

Imports nothing from the simulator, viewer or OpenCV: every function here works
on plain feature matrices, so the strategies run on any data set.
"""
