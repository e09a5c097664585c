"""The words a teacher may use, loaded from ``dialog/data/vocabulary.toml``, and text normalisation."""

from __future__ import annotations

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib
import re
import unicodedata
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

VOCABULARY_FILE = Path(__file__).parent / "data" / "vocabulary.toml"
MAX_ANSWER_CHARS = 300  # longer answers are refused before any matching is tried
COMMANDS = ("help", "why", "undo", "skip", "quit", "dont_know")
_SPLIT = re.compile(r"[^\w'#]+")


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


class VocabularyError(ValueError):
    """The vocabulary file is missing or malformed."""


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

    def command(self, text: str) -> str | None:
        """The command a whole answer names ("why", "undo", ...), or None."""
        key = phrase(text)
        for name in COMMANDS:
            if key in self.commands[name] or clean(text) in self.commands[name]:
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
        with open(path, "rb") as handle:
            data = tomllib.load(handle)
    except FileNotFoundError:
        raise VocabularyError(f"{path}: no such vocabulary file") from None
    except tomllib.TOMLDecodeError as error:
        raise VocabularyError(f"{path}: not valid TOML ({error})") from None
    for table in ("synonyms", "fillers", "negations", "commands", "absent", "confirm", "numbers", "features"):
        if not isinstance(data.get(table), dict):
            raise VocabularyError(f"{path}: missing table [{table}]")
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
    )
