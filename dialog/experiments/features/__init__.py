"""The feature-selection suite kind (thesis ch. 5 study)."""
