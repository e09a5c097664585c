"""Learning a questioning policy by reinforcement learning on teachbot/Questioning-v0 (beyond the thesis)."""
