"""Inverse RL for the decision weights (thesis ch. 7): demonstrations, MaxEnt IRL, rollouts."""
