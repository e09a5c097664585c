"""The answer grammar (docs/dialog.md): a line is taken only when every token of it is consumed.

Property tests generate accepted lines from the grammar and check that one inserted garbage word spoils
them; a corpus of more than 2,000 hostile lines (tests/dialog/data/hostile_answers.txt, alone and mixed
with valid answers, control and direction characters, numbers out of range) is refused everywhere, each
time with the accepted forms.
"""

from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from dialog.language.feature_tree import FeatureTree
from dialog.language.parsing import AnswerParser
from dialog.language.vocabulary import load_vocabulary, tokens

CONCEPTS = ("main dish", "snack", "fruit", "beverage")
N_OBJECTS = 12
PARSER = AnswerParser(CONCEPTS)
VOCABULARY = PARSER.vocabulary
TREE = FeatureTree(("colour.red", "colour.green", "size.length", "weight", "arm.joint1"),
                   [("object/colour", "Redness"), ("object/colour", "Greenness"), ("object/size", "Length"),
                    ("object", "Weight"), ("robot/arm", "Joint 1")])
HOSTILE_FILE = Path(__file__).parent / "data" / "hostile_answers.txt"
PROPERTY = settings(max_examples=150, deadline=None, derandomize=True,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])


def _vocabulary_words() -> frozenset[str]:
    """Every word the grammar gives a meaning to, for any concept of the vocabulary."""
    v = load_vocabulary()
    phrases = [*v.fillers, *v.negations, *v.absent, *v.yes, *v.no, *v.cardinals, *v.ordinals, *v.number_markers,
               *v.ignore_words, *v.use_words, *v.all_words, *v.connectives, "feature", "features", "group", "groups"]
    phrases += [p for forms in v.commands.values() for p in forms]
    phrases += [f for concept in (*v.synonyms, *CONCEPTS) for f in v.forms(concept)]
    return frozenset(word for p in phrases for word in p.split())


VOCABULARY_WORDS = _vocabulary_words()

# -- generators of accepted lines -------------------------------------------------------------------
LABEL_FORMS = sorted((form, concept) for form, owners in PARSER.form_owners.items() if len(owners) == 1
                     for concept in owners)
BEFORE = ["", "it's", "it's a", "I think it's a", "the", "a", "an", "maybe a", "that's a", "this is the", "um, a"]
AFTER = ["", "!", ".", "?", ", I think", " please", ", thanks", "...", " I guess"]
CASES = [str, str.upper, str.title, str.capitalize]


def _line(before: str, core: str, after: str, case, spaces: int) -> str:
    text = " ".join(part for part in (before, core) if part) + after
    return case(" " * spaces + text)


labels = st.builds(lambda form, before, after, case, spaces: (_line(before, form[0], after, case, spaces), form[1]),
                   st.sampled_from(LABEL_FORMS), st.sampled_from(BEFORE), st.sampled_from(AFTER),
                   st.sampled_from(CASES), st.integers(0, 2))
label_numbers = st.builds(lambda k, before, after: (_line(before, str(k), after, str, 0), CONCEPTS[k - 1]),
                          st.integers(1, len(CONCEPTS)), st.sampled_from(["", "it's", "I think it's"]),
                          st.sampled_from(["", ".", "!"]))
_ORDINAL_SUFFIX = {1: "st", 2: "nd", 3: "rd"}
NUMBER_FORMS = [
    lambda k: str(k), lambda k: f"number {k}", lambda k: f"No. {k}", lambda k: f"#{k}", lambda k: f"# {k}",
    lambda k: f"the {k}{_ORDINAL_SUFFIX.get(k, 'th')} one", lambda k: f"object {k}", lambda k: f"item {k}",
    lambda k: f"number {VOCABULARY.cardinals[k]}", lambda k: f"the {VOCABULARY.ordinals[k]}",
    lambda k: f"it's number {k}, the fruit", lambda k: f"fruit number {k}", lambda k: f"the fruit is {k}",
]
demonstrations = st.builds(lambda k, form, after, case: (case(form(k) + after), k - 1),
                           st.integers(1, N_OBJECTS), st.sampled_from(NUMBER_FORMS), st.sampled_from(AFTER),
                           st.sampled_from(CASES))
ABSENT_FORMS = sorted(VOCABULARY.absent) + ["there is no fruit here", "no fruit", "there are no fruits", "none, sorry"]
absences = st.builds(lambda phrase, case: case(phrase), st.sampled_from(ABSENT_FORMS), st.sampled_from(CASES))

garbage_words = st.one_of(
    st.text("abcdefghijklmnopqrstuvwxyz", min_size=1, max_size=9).filter(lambda w: w not in VOCABULARY_WORDS),
    st.text("-+*/\\<>=%$&@^~|`()[]{}", min_size=1, max_size=4),
    st.builds(lambda a, b: a + b, st.sampled_from(["%", "<", "-", "$", "&", "--"]),
              st.text("abcdefghijklmnopqrstuvwxyz0123456789", min_size=1, max_size=6)),
    st.sampled_from(["-1", "2.5", "1e3", "3/4", "-", "script", "alert", "drop", "table", "%s", "<b>"]),
)


def _insert(line: str, word: str, where: int) -> str:
    parts = line.split()
    position = where % (len(parts) + 1)
    return " ".join(parts[:position] + [word] + parts[position:])


# -- properties ----------------------------------------------------------------------------------------
@PROPERTY
@given(st.one_of(labels, label_numbers), garbage_words, st.integers(0, 20))
def test_an_accepted_label_spoilt_by_one_garbage_word_is_refused(case, garbage, where):
    line, concept = case
    assert (PARSER.label(line).kind, PARSER.label(line).value) == ("answer", concept)
    spoilt = PARSER.label(_insert(line, garbage, where))
    assert spoilt.kind == "unreadable" and spoilt.message.endswith(PARSER.label_forms())


@PROPERTY
@given(demonstrations, garbage_words, st.integers(0, 20))
def test_an_accepted_demonstration_spoilt_by_one_garbage_word_is_refused(case, garbage, where):
    line, index = case
    reading = PARSER.demonstration(line, N_OBJECTS, "fruit")
    assert (reading.kind, reading.value) == ("answer", index)
    spoilt = PARSER.demonstration(_insert(line, garbage, where), N_OBJECTS, "fruit")
    assert spoilt.kind == "unreadable" and spoilt.message.endswith(PARSER.demonstration_forms(N_OBJECTS, "fruit"))


@PROPERTY
@given(absences, garbage_words, st.integers(0, 20))
def test_an_absence_spoilt_by_one_garbage_word_is_refused(line, garbage, where):
    assert PARSER.demonstration(line, N_OBJECTS, "fruit").kind == "absent"
    assert PARSER.demonstration(_insert(line, garbage, where), N_OBJECTS, "fruit").kind == "unreadable"


@PROPERTY
@given(st.sampled_from(sorted(p for forms in VOCABULARY.commands.values() for p in forms if p != "?")),
       garbage_words, st.integers(0, 20))
def test_a_command_is_a_whole_line(command, garbage, where):
    assert PARSER.label(command).kind in ("help", "why", "undo", "skip", "quit", "dont_know")
    for reading in (PARSER.label(_insert(command, garbage, where)),
                    PARSER.demonstration(_insert(command, garbage, where), N_OBJECTS, "fruit"),
                    TREE.read(_insert(command, garbage, where))):
        assert reading.kind == "unreadable"


@PROPERTY
@given(st.integers().filter(lambda n: not 1 <= n <= N_OBJECTS), st.sampled_from(["{}", "number {}", "#{}"]))
def test_numbers_out_of_range_are_refused_with_the_range(number, form):
    demo = PARSER.demonstration(form.format(number), N_OBJECTS, "fruit")
    assert demo.kind == "unreadable" and f"1 to {N_OBJECTS}" in demo.message
    label = PARSER.label(str(number))
    assert label.kind == "unreadable" and f"1 to {len(CONCEPTS)}" in label.message


@PROPERTY
@given(st.one_of(
    st.floats(allow_nan=False, allow_infinity=False).map(repr),
    st.builds("{}/{}".format, st.integers(0, 99), st.integers(1, 99)),
    st.builds("{}e{}".format, st.integers(0, 99), st.integers(-9, 9)),
    st.integers(max_value=-1).map(str),
))
def test_negative_and_fractional_numbers_are_refused_with_the_range(text):
    demo = PARSER.demonstration(text, N_OBJECTS, "fruit")
    assert demo.kind == "unreadable" and f"1 to {N_OBJECTS}" in demo.message
    label = PARSER.label(text)
    assert label.kind == "unreadable" and f"1 to {len(CONCEPTS)}" in label.message


@PROPERTY
@given(st.text(max_size=80))
def test_any_text_is_read_or_refused_with_the_accepted_forms(text):
    for reading, accepted in ((PARSER.label(text), PARSER.label_forms()),
                              (PARSER.demonstration(text, N_OBJECTS, "fruit"),
                               PARSER.demonstration_forms(N_OBJECTS, "fruit")),
                              (PARSER.choice(text, ("fruit", "snack")), PARSER.choice_forms(("fruit", "snack"))),
                              (TREE.read(text), "start with 'ignore'")):
        if reading.kind == "unreadable":
            assert accepted in reading.message and "\n" not in reading.message
        if reading.kind == "answer" and isinstance(reading.value, int):
            assert 0 <= reading.value < N_OBJECTS


@PROPERTY
@given(st.text("-+*/\\<>=%$&@^~|`()[]{}#!.,;:'\"", min_size=1, max_size=12))
def test_symbol_lines_are_never_an_answer_or_a_command(text):
    for reading in (PARSER.label(text), PARSER.demonstration(text, N_OBJECTS, "fruit"), TREE.read(text)):
        assert reading.kind == "unreadable"


# -- the hostile corpus --------------------------------------------------------------------------------
def hostile_seeds() -> list[str]:
    lines = HOSTILE_FILE.read_text(encoding="utf-8").splitlines()
    return [line for line in lines if line and not line.startswith("# ")]


def hostile_corpus(seed: int = 13) -> list[str]:
    """The seeds alone, glued to valid answers, wrapped in hostile characters; numbers; huge lines."""
    rng = np.random.default_rng(seed)
    seeds = hostile_seeds()
    valid = ["fruit", "a snack", "3", "number 4", "#4", "none", "skip", "quit", "1.1", "colour", "ignore 2"]
    wrappers = ["\x00", "\x1b[31m", "\x1b]0;x\x07", "\u202e", "\u2066", "\u200f", "\ud800", "\udfff", "\x7f",
                "\x9b", "\ue000", "\x08"]
    lines = list(seeds)
    for text in seeds:
        answer = valid[int(rng.integers(len(valid)))]
        lines += [f"{answer} {text}", f"{text} {answer}"]
        lines.append(text + "\U0001f34e" if rng.random() < 0.5 else "\u05e4\u05e8\u05d9 " + text)
    for answer in valid:
        for wrapper in wrappers:
            lines += [f"{wrapper}{answer}", f"{answer}{wrapper}", f"{answer[:1]}{wrapper}{answer[1:]}"]
    lines += [f"\U0001f34e {v}" for v in valid] + [f"{v} \U0001f600" for v in valid]
    lines += [str(n) for n in (0, 13, 14, 99, 100, 10**6, 10**12, 10**40, -1, -4, -12, -(10**9))]
    lines += [f"number {n}" for n in (0, 13, 1000, -3)] + ["2.5", "1e3", "3/4", "4.0", "-0", ".5", "1,5"]
    lines += ["fruit " + "\u00e9" * 400, "a" * (1 << 20), "4 " * (1 << 19), "number 4" + " " * 400,
              "\U0001f34e" * 1000, "\x00" * 4096]
    while len(lines) < 2100:
        raw = bytes(int(b) for b in rng.integers(0, 256, size=int(rng.integers(2, 24))))
        digit = str(int(rng.integers(1, 10))).encode()
        position = int(rng.integers(len(raw) + 1))
        text = (raw[:position] + digit + raw[position:]).decode("utf-8", errors="replace")
        if any(token.kind != "number" for token in tokens(text)) or "\ufffd" in text:
            lines.append(text)  # random bytes holding one digit, never just the digit
    return lines


def test_the_hostile_corpus_is_large_and_varied():
    corpus = hostile_corpus()
    assert len(hostile_seeds()) >= 180 and len(corpus) >= 2000
    assert max(map(len, corpus)) >= 1 << 20
    assert any("\x00" in line for line in corpus) and any("\ud800" in line for line in corpus)
    assert any("\u202e" in line for line in corpus) and any("\x1b" in line for line in corpus)


def test_no_hostile_line_is_taken_and_every_refusal_lists_the_accepted_forms():
    taken = []
    for line in hostile_corpus():
        readings = [(PARSER.label(line), PARSER.label_forms()),
                    (PARSER.demonstration(line, N_OBJECTS, "fruit"), PARSER.demonstration_forms(N_OBJECTS, "fruit")),
                    (PARSER.choice(line, ("fruit", "snack")), PARSER.choice_forms(("fruit", "snack"))),
                    (TREE.read(line), "start with 'ignore'")]
        for reading, accepted in readings:
            if reading.kind != "unreadable" or accepted not in reading.message or "\n" in reading.message:
                taken.append((line[:60], reading.kind, reading.value))
    assert taken == []


@pytest.mark.parametrize("line", ["-1", "-5", "<script>alert(1)</script>", "DROP TABLE 3; --", "%s", "{1}",
                                  "\x13\ufffd3\ufffd", "4 -", "(4)"])
def test_the_cases_of_the_issue_are_refused(line):
    assert PARSER.demonstration(line, N_OBJECTS, "fruit").kind == "unreadable"
    assert PARSER.label(line).kind == "unreadable"
    assert TREE.read(line).kind == "unreadable"
