"""The decision-theoretic core (thesis eq. 6.2-6.3, 7.1-7.4): candidates, decision features, weights."""
