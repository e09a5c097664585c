"""Recipes (thesis ch. 4): the recipe format, grounding from demonstrations, GMM parameter models."""
