"""The recipes suite kind (thesis ch. 4 experiments)."""
