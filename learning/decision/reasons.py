"""DT's reasons in plain words: the one place that builds DT's "Why?" sentences (no utility numbers in them).

A DT decision compares the best query a* with no query. Each weighted feature f adds the term
w_f * (E[f | a*] - E[f | no query]) to EU(a*) - EU(no query) (thesis eq. 7.1, 7.2); ``utility_terms`` computes
them, the decision carries them (``Decision.terms``) and the reports average them over the quiet turns.
The sentence names the feature whose term decided: for a question the largest term in its favour, for
staying quiet the largest term against asking, set against the largest in favour ("asking now would make my
examples less even, which outweighs what I expect to learn").
"""

from __future__ import annotations

import numpy as np

# Per feature: (why it asks: a clause after "so I ask:", what a question would gain: a noun phrase, what
# asking would cost: a clause). "{concept}" is the concept the question is about.
PHRASES: dict[str, tuple[str, str, str]] = {
    "classifier_discriminability": (
        "I expect to learn the most about {concept} from this {question}", "what I expect to learn",
        "asking now would leave me less able to tell the concepts apart"),
    "class_distribution_uniformity": (
        "it makes my examples more even across the concepts", "making my examples more even",
        "asking now would make my examples less even"),
    "instance_variation": (
        "it makes my examples of {concept} more varied", "making my examples more varied",
        "asking now would make my examples less varied"),
    "prediction_margin": (
        "it should make my guesses about {concept} surer", "making my guesses surer",
        "asking now would make my guesses less sure"),
    "budget_consumption": (
        "I am meant to use my question budget", "using my question budget",
        "asking now would spend question budget I would rather keep"),
    "remaining_time": (
        "I am meant to use the time I have", "using the time I have",
        "asking now would use time I would rather keep"),
    "non_query_time": (
        "I have been quiet long enough", "not staying quiet too long",
        "I would rather stay quiet a while longer"),
    "pace_overrun": (
        "it keeps me to my pace", "keeping to my pace", "asking now would put me ahead of my pace"),
    "feature_query_overdue": (
        "the question about features is due", "asking about the features in time",
        "asking this now would put off the question about features"),
    "concepts_without_example": (
        "it gets me an example of a concept I have none of", "getting an example of every concept",
        "asking now would not get me an example of the concepts I have none of"),
    "unsure_unlabelled": (
        "it gets an object I'm unsure of named", "getting the objects I'm unsure of named",
        "asking now would leave objects I'm unsure of unnamed"),
}
NEGLIGIBLE = 1e-12  # a term this small moved nothing (EU differences of interest are >= 1e-6, resolution.py)


def utility_terms(expected: np.ndarray, weights: np.ndarray, best: int, quiet: int,
                  names: tuple[str, ...]) -> tuple[tuple[str, float], ...]:
    """((feature, w_f * (E[f | best] - E[f | quiet])), ...) for every feature with a non-zero weight, in
    ``names`` order; their sum is EU(best) - EU(quiet)."""
    weights = np.asarray(weights, dtype=float)
    terms = weights * (expected[best] - expected[quiet])
    return tuple((name, float(term)) for name, weight, term in zip(names, weights, terms) if weight != 0)


def _deciding(terms, sign: float) -> str | None:
    """The feature with the largest term of ``sign`` (None when no term of that sign moved anything)."""
    signed = [(sign * value, name) for name, value in terms if sign * value > NEGLIGIBLE]
    return max(signed)[1] if signed else None


def why_ask(terms, concept: str, question: str) -> str:
    """The clause saying what decided a question ("I expect to learn the most about fruit from this label")."""
    feature = _deciding(terms, +1.0)
    if feature is None:  # a tie within rounding: nothing weighed for it in particular
        return "it is the most useful question I have now"
    return PHRASES[feature][0].format(concept=concept, question=question)


def why_quiet(terms) -> str:
    """The clause saying what kept the learner quiet ("asking now would make my examples less even, which
    outweighs what I expect to learn")."""
    against, for_asking = _deciding(terms, -1.0), _deciding(terms, +1.0)
    if against is None:
        return "no question would teach me anything now"
    if for_asking is None:
        return f"{PHRASES[against][2]}, and no question promises anything to make up for it"
    return f"{PHRASES[against][2]}, which outweighs {PHRASES[for_asking][1]}"

