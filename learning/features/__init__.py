"""Feature selection for concept grounding (thesis ch. 5): FI, ES, ER and their information measures."""
