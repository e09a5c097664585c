"""Tolerant reading of the teacher's answers: concept names, object numbers, commands, confirmations.

Nothing is guessed: an answer is read as a value only when the vocabulary or a
small typo distance makes it unambiguous; two close candidates lead to a
question back ("did you mean ...?"); anything else is refused with a message
that lists the accepted forms, and the robot asks again.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from dialog.vocabulary import MAX_ANSWER_CHARS, Vocabulary, clean, load_vocabulary, phrase, plural, words

_DIGITS = re.compile(r"^#?(\d{1,6})(?:st|nd|rd|th)?$")


@dataclass(frozen=True)
class Reading:
    """What one line of the teacher means.

    kind: "answer" (``value`` holds it), "absent" (none in the scene), a
    command ("help", "why", "undo", "skip", "quit", "dont_know"), "choose"
    (``choices`` are close candidates to confirm), "reject" (a confirmation
    was declined) or "unreadable" (``message`` says why and what is accepted).
    """

    kind: str
    value: object = None
    message: str = ""
    choices: tuple = ()


def edit_distance(a: str, b: str, limit: int = 4) -> int:
    """Optimal-string-alignment distance (insert, delete, substitute, swap neighbours), capped at ``limit + 1``."""
    if abs(len(a) - len(b)) > limit:
        return limit + 1
    previous2: list[int] | None = None
    previous = list(range(len(b) + 1))
    for i in range(1, len(a) + 1):
        current = [i] + [0] * len(b)
        for j in range(1, len(b) + 1):
            cost = 0 if a[i - 1] == b[j - 1] else 1
            current[j] = min(previous[j] + 1, current[j - 1] + 1, previous[j - 1] + cost)
            if previous2 is not None and i > 1 and j > 1 and a[i - 1] == b[j - 2] and a[i - 2] == b[j - 1]:
                current[j] = min(current[j], previous2[j - 2] + 1)
        if min(current) > limit:
            return limit + 1
        previous2, previous = previous, current
    return min(previous[-1], limit + 1)


def typo_tolerance(form: str) -> int:
    """How many edits still count as a typo of ``form``: none for very short words, more for long ones."""
    n = len(form.replace(" ", ""))
    return 0 if n <= 3 else 1 if n <= 5 else 2 if n <= 10 else 3


class AnswerParser:
    """Reads answers for one task's concepts with one vocabulary."""

    def __init__(self, concepts, vocabulary: Vocabulary | None = None):
        self.concepts = tuple(concepts)
        self.vocabulary = vocabulary or load_vocabulary()
        self.form_owners: dict[str, set[str]] = {}
        for concept in self.concepts:
            for form in self.vocabulary.forms(concept):
                self.form_owners.setdefault(form, set()).add(concept)
        for concept in self.concepts:  # a concept's own name always means that concept
            for form in (phrase(concept),):
                self.form_owners[form] = {concept}
        self._longest_form = max((len(f.split()) for f in self.form_owners), default=1)
        # typos are matched against the concept names and their plurals only, never against synonyms
        self.name_forms = {c: {phrase(c), phrase(plural(c))} | {phrase(p) for p in self.vocabulary.plurals.get(c, ())}
                           for c in self.concepts}

    # -- shared ---------------------------------------------------------------------
    def _precheck(self, text: str) -> Reading | None:
        if len(text) > MAX_ANSWER_CHARS:
            return Reading("unreadable", message=f"That answer is too long ({len(text)} characters; "
                                                 f"at most {MAX_ANSWER_CHARS}).")
        if not phrase(text) and clean(text) not in self.vocabulary.commands["help"]:
            return Reading("unreadable", message="I got an empty answer." if not clean(text) else
                           f"I can't read '{clean(text)[:40]}'.")
        command = self.vocabulary.command(text)
        return Reading(command) if command else None

    def concept_list(self) -> str:
        return ", ".join(f"{i + 1} {c}" for i, c in enumerate(self.concepts))

    def _number_words(self, tokens: list[str]) -> list[int]:
        """Object numbers in the words: digits, '#4', '4th', number words after a marker or on their own."""
        vocabulary = self.vocabulary
        numbers = []
        for position, token in enumerate(tokens):
            match = _DIGITS.match(token)
            if match:
                numbers.append(int(match.group(1)))
            elif token in vocabulary.ordinals:
                numbers.append(vocabulary.ordinals.index(token))
            elif token in vocabulary.cardinals:
                marked = position > 0 and tokens[position - 1] in vocabulary.number_markers
                if marked or len(tokens) == 1 or token != "one":
                    numbers.append(vocabulary.cardinals.index(token))
        return numbers

    # -- label queries ----------------------------------------------------------------
    def concepts_mentioned(self, tokens: list[str]) -> set[str]:
        """Concepts named exactly by some run of words (longest forms first)."""
        found: set[str] = set()
        for size in range(min(self._longest_form, len(tokens)), 0, -1):
            for start in range(len(tokens) - size + 1):
                owners = self.form_owners.get(" ".join(tokens[start:start + size]))
                if owners:
                    found |= owners
        return found

    def _fuzzy(self, candidates: list[str]) -> dict[str, int]:
        """Best typo distance per concept over the candidate strings (within each form's tolerance + 1)."""
        best: dict[str, int] = {}
        for text in candidates:
            for concept, forms in self.name_forms.items():
                for form in forms:
                    tolerance = typo_tolerance(form)
                    if tolerance == 0 or not text or text[0] != form[0]:
                        continue
                    distance = edit_distance(text, form, tolerance + 1)
                    if distance <= tolerance + 1 and distance < best.get(concept, 99):
                        best[concept] = distance
        return best

    def label(self, text: str) -> Reading:
        """A concept name for a label query ("a fruit", "Fruits", "frut", "3" from the numbered list)."""
        early = self._precheck(text)
        if early:
            return early
        accepted = (f"Please name one of: {', '.join(self.concepts)} (or its number: {self.concept_list()}); "
                    "or say 'don't know', 'skip', 'why', 'undo', 'help' or 'quit'.")
        tokens = words(clean(text))
        if any(t in self.vocabulary.negations for t in tokens):
            return Reading("unreadable", message=f"I can only learn what it is, not what it isn't. {accepted}")
        content = [t for t in tokens if t not in self.vocabulary.fillers]
        mentioned = self.concepts_mentioned(tokens)
        if len(mentioned) == 1:
            return Reading("answer", mentioned.pop())
        if len(mentioned) > 1:
            choices = tuple(c for c in self.concepts if c in mentioned)
            return Reading("choose", choices=choices, message=f"You named {' and '.join(choices)}.")
        numbers = self._number_words(content) if len(content) == 1 else []
        if numbers:
            if 1 <= numbers[0] <= len(self.concepts):
                return Reading("answer", self.concepts[numbers[0] - 1])
            return Reading("unreadable", message=f"There is no concept number {numbers[0]}. {accepted}")
        if not content or len(" ".join(content)) > 60:
            return Reading("unreadable", message=f"I didn't understand '{clean(text)[:60]}'. {accepted}")
        candidates = [" ".join(content)] + [" ".join(content[i:i + n]) for n in (1, 2, 3)
                                            for i in range(len(content) - n + 1)]
        best = self._fuzzy(list(dict.fromkeys(candidates)))
        if best:
            top = min(best.values())
            close = tuple(c for c in self.concepts if c in best and best[c] <= top + 1)
            if len(close) == 1 and top <= typo_tolerance(close[0]):
                return Reading("answer", close[0], message=f"(I take '{' '.join(content)}' as '{close[0]}'.)")
            if close:
                return Reading("choose", choices=close, message=f"'{' '.join(content)}' is close to more than "
                                                                "one word I know." if len(close) > 1 else "")
        return Reading("unreadable", message=f"I didn't understand '{clean(text)[:60]}'. {accepted}")

    # -- demonstration queries ---------------------------------------------------------
    def demonstration(self, text: str, n_objects: int, concept: str) -> Reading:
        """An object number ("4", "number four", "the 4th") or "none" when no example is in the scene."""
        early = self._precheck(text)
        if early:
            return early
        accepted = (f"Please give the number of a {concept} (1 to {n_objects}), or say 'none' if there is no "
                    f"{concept} here; or 'don't know', 'skip', 'why', 'undo', 'help' or 'quit'.")
        tokens = words(clean(text))
        concept_words = set(phrase(concept).split())
        for form, owners in self.form_owners.items():
            if concept in owners:
                concept_words.update(form.split())
        remainder = [t for t in tokens if t not in self.vocabulary.fillers and t not in concept_words]
        markers = self.vocabulary.number_markers
        negated = [t in self.vocabulary.negations and not (t in markers and i + 1 < len(tokens)
                                                           and self._number_words([tokens[i + 1]]))
                   for i, t in enumerate(tokens)]
        numbers = self._number_words([t for t, negation in zip(tokens, negated) if not negation])
        joined = " ".join(remainder)
        whole = " ".join(t for t in tokens if t not in concept_words)
        if not numbers and (joined in self.vocabulary.absent or whole in self.vocabulary.absent
                            or (remainder and remainder[0] in ("no", "none") and len(remainder) <= 3)):
            return Reading("absent")
        if any(negated):
            return Reading("unreadable", message=f"Please tell me which one it is, not which it isn't. {accepted}")
        if len(set(numbers)) > 1:
            return Reading("unreadable", message=f"One number please, you gave {sorted(set(numbers))}. {accepted}")
        if numbers:
            number = numbers[0]
            if not 1 <= number <= n_objects:
                return Reading("unreadable", message=f"There is no object {number} in this scene. {accepted}")
            return Reading("answer", number - 1)
        return Reading("unreadable", message=f"I didn't understand '{clean(text)[:60]}'. {accepted}")

    # -- confirmations -----------------------------------------------------------------
    def choice(self, text: str, choices: tuple[str, ...]) -> Reading:
        """Pick one of ``choices`` by number or name; "yes" picks the only one; "no" declines."""
        if len(text) > MAX_ANSWER_CHARS:
            return Reading("unreadable", message=f"That answer is too long ({len(text)} characters).")
        key = phrase(text)
        accepted = ("Type " + " or ".join(f"{i + 1} for {c}" for i, c in enumerate(choices))
                    + (", yes or no." if len(choices) == 1 else ", or 'no' to answer the question again."))
        if key in self.vocabulary.yes and len(choices) == 1:
            return Reading("answer", choices[0])
        if key in self.vocabulary.no:
            return Reading("reject")
        command = self.vocabulary.command(text)
        if command in ("help", "why", "undo", "skip", "quit", "dont_know"):
            return Reading(command)
        numbers = self._number_words(words(clean(text)))
        if len(numbers) == 1 and 1 <= numbers[0] <= len(choices):
            return Reading("answer", choices[numbers[0] - 1])
        named = self.concepts_mentioned(words(clean(text))) & set(choices)
        if len(named) == 1:
            return Reading("answer", named.pop())
        return Reading("unreadable", message=f"I didn't get that. {accepted}")
