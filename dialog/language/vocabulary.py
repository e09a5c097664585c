"""The words a teacher may use, loaded from ``dialog/data/vocabulary.toml``, and text normalisation."""

from __future__ import annotations

import re
import unicodedata
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

from learning.datafiles import MissingDataFileError, check_keys, read_toml, section
from learning.errors import DataFileError

VOCABULARY_FILE = Path(__file__).parents[1] / "data" / "vocabulary.toml"
MAX_ANSWER_CHARS = 300  # longer answers are refused before any matching is tried
COMMANDS = ("help", "why", "undo", "skip", "quit", "dont_know")
_SPLIT = re.compile(r"[^\w'#]+")
# the answer grammar's pieces (docs/dialog.md, "The answer grammar")
_PIECES = re.compile(r"[\s,;]+")
_LEADING = "\"'\u00ab\u201c\u201e\u00bf\u00a1"  # opening quotes and marks, dropped before a word
_TRAILING = ".,!?;:\"'\u00bb\u201d"  # sentence punctuation and closing quotes, dropped after a word
_STOPS = frozenset(".!?")  # a piece made only of these ("...", "?!") is punctuation between words
_WORD = re.compile(r"[^\W\d_]+(?:'[^\W\d_]+)*")
_NUMBER = re.compile(r"#?([0-9]+)(?:st|nd|rd|th)?")
_NUMBER_LIKE = re.compile(r"#?[-+\u2212\u00b1]?[0-9]*(?:[./:\u2044][0-9]+)*(?:e[-+]?[0-9]+)?(?:st|nd|rd|th|%)?")
_BIDI = frozenset("\u061c\u200e\u200f\u202a\u202b\u202c\u202d\u202e\u2066\u2067\u2068\u2069")
LARGEST_NUMBER = 10**9  # longer digit strings are read as this (out of every range)


def clean(text: str) -> str:
    """Unicode-normalise, drop control and format characters and accents, fold case, collapse whitespace."""
    text = unicodedata.normalize("NFKC", text).replace("\u2019", "'").replace("\u2018", "'")
    kept = []
    for ch in unicodedata.normalize("NFKD", text):
        category = unicodedata.category(ch)
        if category[0] == "Z" or ch in "\t\n\r\v\f":
            kept.append(" ")
        elif category[0] != "C" and not unicodedata.combining(ch):
            kept.append(ch)
    return " ".join("".join(kept).casefold().split())


@dataclass(frozen=True)
class Token:
    """One piece of a cleaned answer.

    kind: "word" (letters, inner apostrophes), "number" (``value``: a whole
    number as written, "4", "#4", "4th"), "mark" (a lone '#'), "bad_number"
    (negative, fractional, exponent: "-1", "2.5", "1e3", "3/4") or "garbage"
    (anything else: symbols, markup, digits inside words).
    """

    text: str
    kind: str
    value: int | None = None


def _token(core: str) -> list[Token]:
    match = _NUMBER.fullmatch(core)
    if match:
        digits = match.group(1)
        return [Token(core, "number", int(digits) if len(digits) < 10 else LARGEST_NUMBER)]
    if core == "#":
        return [Token(core, "mark")]
    if _WORD.fullmatch(core):
        return [Token(core, "word")]
    parts = re.split(r"[-_]", core)
    if len(parts) > 1 and all(_WORD.fullmatch(part) for part in parts):  # main-dish, main_dish
        return [Token(part, "word") for part in parts]
    if any(ch.isdigit() for ch in core) and _NUMBER_LIKE.fullmatch(core):
        return [Token(core, "bad_number")]
    return [Token(core, "garbage")]


def tokens(cleaned: str) -> list[Token]:
    """The grammar's tokens of a cleaned answer: split at spaces, commas and semicolons; opening quotes before
    and sentence punctuation after a piece are dropped, everything else stays and is classified."""
    out: list[Token] = []
    for piece in _PIECES.split(cleaned):
        core = piece.lstrip(_LEADING).rstrip(_TRAILING)
        if core:
            out.extend(_token(core))
        elif piece and not set(piece) <= _STOPS:
            out.append(Token(piece, "garbage"))
    return out


def word_key(cleaned: str) -> str | None:
    """A cleaned line as its words joined by spaces, or None when some token is not a word."""
    pieces = tokens(cleaned)
    return " ".join(t.text for t in pieces) if pieces and all(t.kind == "word" for t in pieces) else None


def refused_characters(text: str) -> str | None:
    """What makes a raw line unreadable before any matching: control, direction, surrogate or unassigned
    characters (tabs and line ends are fine; invisible format characters such as zero-width spaces are dropped)."""
    for ch in text:
        if ch in "\t\n\r\v\f":
            continue
        category = unicodedata.category(ch)
        if category == "Cc":
            return f"a control character (U+{ord(ch):04X})"
        if ch in _BIDI:
            return f"a text-direction character (U+{ord(ch):04X})"
        if category in ("Cs", "Co", "Cn"):
            return f"an invalid or private character (U+{ord(ch):04X})"
    return None


def words(text: str) -> list[str]:
    """The words of a cleaned answer: letters, digits, apostrophes and '#' kept, everything else splits."""
    return [w.strip("'") for w in _SPLIT.split(text.replace("_", " ")) if w.strip("'")]


def phrase(text: str) -> str:
    """A cleaned answer as space-separated words (punctuation gone)."""
    return " ".join(words(clean(text)))


def plural(word_or_phrase: str) -> str:
    """English plural of the last word by the regular rules (fruit -> fruits, berry -> berries)."""
    head, _, last = word_or_phrase.rpartition(" ")
    if last.endswith("y") and len(last) > 1 and last[-2] not in "aeiou":
        last = last[:-1] + "ies"
    elif last.endswith(("s", "x", "z", "ch", "sh")):
        last = last + "es"
    else:
        last = last + "s"
    return f"{head} {last}".strip()


class VocabularyError(DataFileError):
    """The vocabulary file is missing or malformed."""


VOCABULARY_TABLES = ("synonyms", "fillers", "negations", "commands", "absent", "confirm", "numbers", "features")
OPTIONAL_TABLES = ("plurals", "connectives")


@dataclass(frozen=True)
class Vocabulary:
    synonyms: dict[str, tuple[str, ...]]
    plurals: dict[str, tuple[str, ...]]
    fillers: frozenset[str]
    negations: frozenset[str]
    commands: dict[str, frozenset[str]]
    absent: frozenset[str]
    yes: frozenset[str]
    no: frozenset[str]
    cardinals: tuple[str, ...]
    ordinals: tuple[str, ...]
    number_markers: frozenset[str]
    ignore_words: tuple[str, ...]
    use_words: tuple[str, ...]
    all_words: frozenset[str]
    connectives: frozenset[str] = frozenset()  # words allowed between two named concepts ("fruit or snack")

    def command(self, text: str) -> str | None:
        """The command a whole answer names ("why", "undo", ...), or None; every token must be a word
        ("%s" is no "s")."""
        cleaned = clean(text)
        key = word_key(cleaned)
        for name in COMMANDS:
            if key in self.commands[name] or cleaned in self.commands[name]:
                return name
        return None

    def forms(self, concept: str) -> set[str]:
        """Every accepted way to say ``concept``: name, synonyms and their plurals, normalised."""
        base = [concept, *self.synonyms.get(concept, ())]
        result = set()
        for entry in base:
            key = phrase(entry)
            result.update({key, plural(key), *(phrase(p) for p in self.plurals.get(entry, ()))})
        result.update(phrase(p) for p in self.plurals.get(concept, ()))
        return {form for form in result if form}


def _strings(table: dict, key: str, where: str) -> tuple[str, ...]:
    values = table.get(key)
    if not isinstance(values, list) or not all(isinstance(v, str) and v.strip() for v in values):
        raise VocabularyError(f"{where}: '{key}' must be a list of non-empty strings")
    return tuple(values)


def _normalised(values) -> frozenset[str]:
    return frozenset(phrase(v) or clean(v) for v in values)


@lru_cache(maxsize=4)
def load_vocabulary(path: str | Path = VOCABULARY_FILE) -> Vocabulary:
    """Read and check a vocabulary file; errors name the file and the table."""
    path = Path(path)
    try:
        data = read_toml(path, "vocabulary")
        check_keys(data, str(path), required=VOCABULARY_TABLES, optional=OPTIONAL_TABLES)
        for table in VOCABULARY_TABLES + OPTIONAL_TABLES:
            if table in data:
                section(data, table, str(path))
    except MissingDataFileError:
        raise VocabularyError(f"{path}: no such vocabulary file") from None
    except DataFileError as error:
        raise VocabularyError(str(error)) from None
    synonyms = {concept: _strings(data["synonyms"], concept, f"{path} [synonyms]") for concept in data["synonyms"]}
    plurals = {word: _strings(data.get("plurals", {}), word, f"{path} [plurals]") for word in data.get("plurals", {})}
    commands = {name: _normalised(_strings(data["commands"], name, f"{path} [commands]")) for name in COMMANDS}
    numbers = data["numbers"]
    features = data["features"]
    return Vocabulary(
        synonyms=synonyms,
        plurals=plurals,
        fillers=_normalised(_strings(data["fillers"], "words", f"{path} [fillers]")),
        negations=_normalised(_strings(data["negations"], "words", f"{path} [negations]")),
        commands=commands,
        absent=_normalised(_strings(data["absent"], "phrases", f"{path} [absent]")),
        yes=_normalised(_strings(data["confirm"], "yes", f"{path} [confirm]")),
        no=_normalised(_strings(data["confirm"], "no", f"{path} [confirm]")),
        cardinals=tuple(phrase(w) for w in _strings(numbers, "cardinals", f"{path} [numbers]")),
        ordinals=tuple(phrase(w) for w in _strings(numbers, "ordinals", f"{path} [numbers]")),
        number_markers=frozenset(clean(w) for w in _strings(numbers, "markers", f"{path} [numbers]")),
        ignore_words=tuple(sorted((phrase(w) for w in _strings(features, "ignore", f"{path} [features]")),
                                  key=lambda w: -len(w))),
        use_words=tuple(sorted((phrase(w) for w in _strings(features, "use", f"{path} [features]")),
                               key=lambda w: -len(w))),
        all_words=_normalised(_strings(features, "all", f"{path} [features]")),
        connectives=_normalised(_strings(data["connectives"], "words", f"{path} [connectives]"))
        if "connectives" in data else frozenset(),
    )
