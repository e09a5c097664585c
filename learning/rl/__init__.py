"""A learned questioning policy: the fixed observation and action slots (observation.py) and the policy file
(policy_file.py). Training lives on the application side (dialog/rl/gym_env.py, dialog/rl/)."""
