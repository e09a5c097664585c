"""Expert questioning mode (thesis §7.3.2, §7.4.1): a person or the scripted expert chooses the robot's questions."""
