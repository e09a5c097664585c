"""Recipe scenes in the simulator: layouts, set-up from task files, tracking objects."""
