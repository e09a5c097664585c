"""Reading the teacher's answers by one grammar: concept names, object numbers, commands, confirmations.

Nothing is guessed: a line is taken only when every token of it is consumed by
the grammar (fillers, number markers, one number or one concept, the concept's
own words for a demonstration; a command is a whole line). Two close
candidates lead to a question back ("did you mean ...?"); anything else is
refused with a message that says what was wrong and lists the accepted forms.
The grammar is written down in docs/dialog.md ("The answer grammar").
"""

from __future__ import annotations

from dataclasses import dataclass

from dialog.language.vocabulary import (
    MAX_ANSWER_CHARS,
    Token,
    Vocabulary,
    clean,
    load_vocabulary,
    phrase,
    plural,
    refused_characters,
    tokens,
    word_key,
)

COMMAND_FORMS = "'don't know', 'skip', 'why', 'undo', 'help' or 'quit'"


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
            self.form_owners[phrase(concept)] = {concept}
        self._longest_form = max((len(f.split()) for f in self.form_owners), default=1)
        self._absent = {tuple(p.split()) for p in self.vocabulary.absent}
        self._longest_absent = max((len(p) for p in self._absent), default=1)
        # typos are matched against the concept names and their plurals only, never against synonyms
        self.name_forms = {c: {phrase(c), phrase(plural(c))} | {phrase(p) for p in self.vocabulary.plurals.get(c, ())}
                           for c in self.concepts}

    # -- accepted forms, said with every refusal ------------------------------------------
    def concept_list(self) -> str:
        return ", ".join(f"{i + 1} {c}" for i, c in enumerate(self.concepts))

    def label_forms(self) -> str:
        return (f"Please name one of: {', '.join(self.concepts)} (or its number: {self.concept_list()}); "
                f"or say {COMMAND_FORMS}.")

    @staticmethod
    def demonstration_forms(n_objects: int, concept: str) -> str:
        return (f"Please give the number of a {concept} (1 to {n_objects}), or say 'none' if there is no "
                f"{concept} here; or {COMMAND_FORMS}.")

    @staticmethod
    def choice_forms(choices: tuple[str, ...]) -> str:
        return ("Type " + " or ".join(f"{i + 1} for {c}" for i, c in enumerate(choices))
                + (", yes or no." if len(choices) == 1 else ", or 'no' to answer the question again."))

    # -- shared ---------------------------------------------------------------------
    def _precheck(self, text: str, accepted: str) -> tuple[Reading | None, list[Token]]:
        """Too long, odd characters, empty, or a command: the reading; else the line's tokens."""
        if len(text) > MAX_ANSWER_CHARS:
            return Reading("unreadable", message=f"That answer is too long ({len(text)} characters; "
                                                 f"at most {MAX_ANSWER_CHARS}). {accepted}"), []
        odd = refused_characters(text)
        if odd:
            return Reading("unreadable", message=f"That answer holds {odd}; please type plain text. {accepted}"), []
        cleaned = clean(text)
        if not cleaned:
            return Reading("unreadable", message=f"I got an empty answer. {accepted}"), []
        command = self.vocabulary.command(text)
        if command:
            return Reading(command), []
        pieces = tokens(cleaned)
        if not pieces:
            return Reading("unreadable", message=f"I can't read '{cleaned[:40]}'. {accepted}"), []
        return None, pieces

    @staticmethod
    def _odd_tokens(pieces: list[Token], accepted: str, what: str, high: int) -> Reading | None:
        """Symbols, markup or a number that is not a whole positive number: refused, the range named."""
        garbage = [t.text for t in pieces if t.kind == "garbage"]
        if garbage:
            return Reading("unreadable", message=f"I can't read {_quoted(garbage)} in that answer. {accepted}")
        bad = [t.text for t in pieces if t.kind == "bad_number"]
        if bad:
            return Reading("unreadable", message=f"I can't take {_quoted(bad)}: {what}s are whole numbers "
                                                 f"from 1 to {high}. {accepted}")
        return None

    def _number(self, pieces: list[Token], position: int) -> int | None:
        """The number token ``position`` holds: digits ('4', '#4', '4th') or a number word ('four', 'fourth')."""
        token = pieces[position]
        if token.kind == "number":
            return token.value
        if token.kind != "word":
            return None
        if token.text in self.vocabulary.ordinals:
            return self.vocabulary.ordinals.index(token.text)
        if token.text in self.vocabulary.cardinals:
            marked = position > 0 and self._is_marker(pieces, position - 1)
            if token.text != "one" or marked or len(pieces) == 1:  # "that one" is a filler, "number one" is 1
                return self.vocabulary.cardinals.index(token.text)
        return None

    def _is_marker(self, pieces: list[Token], position: int) -> bool:
        token = pieces[position]
        return token.kind == "mark" or (token.kind == "word" and token.text in self.vocabulary.number_markers)

    def _segment(self, pieces: list[Token]) -> tuple[list[set[str]], list[Token]]:
        """Concept forms (longest first, left to right), fillers, and the tokens left over."""
        named: list[set[str]] = []
        leftover: list[Token] = []
        position = 0
        while position < len(pieces):
            for size in range(min(self._longest_form, len(pieces) - position), 0, -1):
                run = pieces[position:position + size]
                owners = self.form_owners.get(" ".join(t.text for t in run)) if all(
                    t.kind == "word" for t in run) else None
                if owners:
                    named.append(owners)
                    position += size
                    break
            else:
                token = pieces[position]
                if not (token.kind == "word" and token.text in self.vocabulary.fillers):
                    leftover.append(token)
                position += 1
        return named, leftover

    def concepts_mentioned(self, words_of_answer: list[str]) -> set[str]:
        """Concepts named by forms in a list of words (longest forms first)."""
        named, _ = self._segment([Token(w, "word") for w in words_of_answer])
        return set().union(*named) if named else set()

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

    def _typo_of_whole_line(self, pieces: list[Token]) -> Reading | None:
        """The one concept whose whole name the line's words are a typo of ("main dsh" -> main dish), else None."""
        words = [t for t in pieces if not (t.kind == "word" and t.text in self.vocabulary.fillers)]
        content = " ".join(t.text for t in words)
        if not words or not all(t.kind == "word" for t in words) or len(content) > 60:
            return None
        best = self._fuzzy([content])
        if not best:
            return None
        top = min(best.values())
        close = [c for c in self.concepts if c in best and best[c] <= top + 1]
        if len(close) == 1 and top <= typo_tolerance(phrase(close[0])):
            return Reading("answer", close[0], message=f"(I take '{content}' as '{close[0]}'.)")
        return None

    # -- label queries ----------------------------------------------------------------
    def label(self, text: str) -> Reading:
        """A concept name for a label query ("a fruit", "Fruits", "frut", "3" from the numbered list)."""
        accepted = self.label_forms()
        early, pieces = self._precheck(text, accepted)
        if early:
            return early
        odd = self._odd_tokens(pieces, accepted, "concept number", len(self.concepts))
        if odd:
            return odd
        shown = clean(text)[:60]
        if any(t.text in self.vocabulary.negations for t in pieces):
            return Reading("unreadable", message=f"I can only learn what it is, not what it isn't. {accepted}")
        named, leftover = self._segment(pieces)
        mentioned = tuple(c for c in self.concepts if any(c in owners for owners in named))
        if leftover:  # "main dihs": a synonym ("main") took one word of a mistyped two-word name
            whole = self._typo_of_whole_line(pieces)
            if whole:
                return whole
        if mentioned:
            if len(mentioned) == 1 and not leftover:
                return Reading("answer", mentioned[0])
            if len(mentioned) > 1 and all(t.text in self.vocabulary.connectives for t in leftover):
                return Reading("choose", choices=mentioned, message=f"You named {' and '.join(mentioned)}.")
            return Reading("unreadable", message=f"{_not_understood(shown, leftover)} {accepted}")
        if len(leftover) == 1 and leftover[0].kind in ("number", "word"):
            number = self._number(leftover, 0)
            if number is not None:
                if 1 <= number <= len(self.concepts):
                    return Reading("answer", self.concepts[number - 1])
                return Reading("unreadable", message=f"There is no concept number {_shown_number(leftover[0])} "
                                                     f"(they are numbered 1 to {len(self.concepts)}). {accepted}")
        content = " ".join(t.text for t in leftover)
        if leftover and all(t.kind == "word" for t in leftover) and len(content) <= 60:
            best = self._fuzzy([content])
            if best:
                top = min(best.values())
                close = tuple(c for c in self.concepts if c in best and best[c] <= top + 1)
                if len(close) == 1 and top <= typo_tolerance(close[0]):
                    return Reading("answer", close[0], message=f"(I take '{content}' as '{close[0]}'.)")
                return Reading("choose", choices=close, message=f"'{content}' is close to more than "
                                                                "one word I know." if len(close) > 1 else "")
        return Reading("unreadable", message=f"I didn't understand '{shown}'. {accepted}")

    # -- demonstration queries ---------------------------------------------------------
    def demonstration(self, text: str, n_objects: int, concept: str) -> Reading:
        """An object number ("4", "number four", "the 4th") or "none" when no example is in the scene."""
        accepted = self.demonstration_forms(n_objects, concept)
        early, pieces = self._precheck(text, accepted)
        if early:
            return early
        odd = self._odd_tokens(pieces, accepted, "object number", n_objects)
        if odd:
            return odd
        concept_words = {word for form, owners in self.form_owners.items() if concept in owners
                         for word in form.split()} | set(phrase(concept).split())
        consumed = [False] * len(pieces)
        numbers: list[tuple[int, Token]] = []
        for position in range(len(pieces)):
            number = self._number(pieces, position)
            if number is not None:
                numbers.append((number, pieces[position]))
                consumed[position] = True
                if position > 0 and self._is_marker(pieces, position - 1):
                    consumed[position - 1] = True
        absent = self._mark_absent(pieces, [i for i in range(len(pieces)) if not consumed[i]], consumed)
        rest = [i for i, t in enumerate(pieces) if not consumed[i] and t.text not in concept_words]
        absent += self._mark_absent(pieces, rest, consumed)  # "there is no fruit here"
        vocabulary = self.vocabulary
        leftover = [pieces[i] for i in rest if not consumed[i] and pieces[i].text not in vocabulary.fillers]
        if numbers and any(t.text in vocabulary.negations for t in leftover):
            return Reading("unreadable", message=f"Please tell me which one it is, not which it isn't. {accepted}")
        distinct = sorted({n for n, _ in numbers})
        if len(distinct) > 1:
            written = list(dict.fromkeys(token.text for _, token in numbers))  # as typed, in the order typed
            return Reading("unreadable", message=f"One number please, you gave {_quoted(written)}. {accepted}")
        if leftover:
            return Reading("unreadable", message=f"{_not_understood(clean(text)[:60], leftover)} {accepted}")
        if numbers and absent:
            return Reading("unreadable", message=f"You gave a number and said there is none. {accepted}")
        if numbers:
            number, token = numbers[0]
            if not 1 <= number <= n_objects:
                return Reading("unreadable", message=f"There is no object {_shown_number(token)} in this scene "
                                                     f"(they are numbered 1 to {n_objects}). {accepted}")
            return Reading("answer", number - 1)
        if absent:
            return Reading("absent")
        return Reading("unreadable", message=f"I didn't understand '{clean(text)[:60]}'. {accepted}")

    def _mark_absent(self, pieces: list[Token], positions: list[int], consumed: list[bool]) -> int:
        """Mark runs of ``positions`` that read as an absent phrase ("there is no", "not here"); how many."""
        runs, index = 0, 0
        while index < len(positions):
            for size in range(min(self._longest_absent, len(positions) - index), 0, -1):
                run = positions[index:index + size]
                if tuple(pieces[i].text for i in run) in self._absent:
                    for i in run:
                        consumed[i] = True
                    runs += 1
                    index += size
                    break
            else:
                index += 1
        return runs

    # -- confirmations -----------------------------------------------------------------
    def choice(self, text: str, choices: tuple[str, ...]) -> Reading:
        """Pick one of ``choices`` by number or name; "yes" picks the only one; "no" declines."""
        accepted = self.choice_forms(choices)
        vocabulary = self.vocabulary
        if len(text) <= MAX_ANSWER_CHARS and not refused_characters(text) and word_key(clean(text)) in vocabulary.no:
            return Reading("reject")  # before commands: "wrong" here declines the choice
        early, pieces = self._precheck(text, accepted)
        if early:
            return early
        odd = self._odd_tokens(pieces, accepted, "choice number", len(choices))
        if odd:
            return odd
        content = [t for t in pieces if not (t.kind == "word" and t.text in vocabulary.fillers)]
        whole = " ".join(t.text for t in pieces)
        core = " ".join(t.text for t in content)
        if (whole in vocabulary.yes or core in vocabulary.yes) and len(choices) == 1:
            return Reading("answer", choices[0])
        if core in vocabulary.no:
            return Reading("reject")
        if len(content) == 1:
            number = self._number(content, 0)
            if number is not None and 1 <= number <= len(choices):
                return Reading("answer", choices[number - 1])
        named, leftover = self._segment(pieces)
        picked = set().union(*named) & set(choices) if named else set()
        if len(picked) == 1 and not leftover and all(owners & set(choices) for owners in named):
            return Reading("answer", picked.pop())
        return Reading("unreadable", message=f"I didn't get that. {accepted}")


def _quoted(items) -> str:
    """'a', 'b' and 'c' (at most five, each cut to 20 characters)."""
    texts = [f"'{(item.text if isinstance(item, Token) else item)[:20]}'" for item in items][:5]
    return texts[0] if len(texts) == 1 else ", ".join(texts[:-1]) + " and " + texts[-1]


def _not_understood(shown: str, leftover: list[Token]) -> str:
    """The refusal of a line with words left over, naming each once."""
    names = list(dict.fromkeys(t.text for t in leftover))
    verb = "fits" if len(names) == 1 else "fit"
    return f"I didn't understand '{shown}' ({_quoted(names)} {verb} no accepted form)."


def _shown_number(token: Token) -> str:
    return token.text if len(token.text) <= 12 else token.text[:12] + "..."
