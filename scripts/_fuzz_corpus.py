"""The hostile corpus of ``scripts/fuzz_teach.py``: lines that are no answer, and the answers that move a session on.

Every hostile line must be refused by ``teachbot teach`` (asked again, or asked
back "did you mean"); none names a concept, a command or a vocabulary word on
purpose. Numbers are made out of range for the question they are sent to.
Lines are bytes: invalid UTF-8 and control characters are part of the corpus.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

MEGABYTE = 1 << 20
CTRL_C, CTRL_D, CTRL_Z = b"\x03", b"\x04", b"\x1a"
LITERAL_NEXT = b"\x16"  # ^V: the terminal hands the next byte over as it is instead of acting on it

STATIC = {
    "empty": ["", " ", "   ", "\t", "\t \t", "\u00a0", "\u3000"],
    "invalid-utf8": [b"\xff", b"\xfe\xff", b"\xc3\x28", b"\xed\xa0\x80", b"\xf8\x88\x80\x80\x80", b"\xe2\x82",
                     b"caf\xe9", b"\xc0\xaf", b"\x80\x80\x80"],
    "nul": ["\x00", "\x00\x00\x00", "a\x00b", "\x00\x00x\x00"],
    "escape": ["\x1b[3~", "\x1b[1;5C", "\x1b[A", "\x1b[2J\x1b[H", "\x1b[31mxyz\x1b[0m", "\x1b]0;title\x07",
               "\x1b[6n", "\x1bOP", "\x1b[200~pasted\x1b[201~", "\x1b[?1049h", "\x1bc", "\x1b[999;999H"],
    "control": ["\x07\x07", "ab\x08\x08cd", "x\ry", "\x7f\x7f", "\x1c", "\x0b\x0c", "\x1b", "\x15\x17\x12"],
    "emoji": ["\U0001f34e", "\U0001f44d\U0001f44d", "\U0001f3f3\ufe0f\u200d\U0001f308", "\U0001f916\u2753",
              "\U0001f600" * 40, "\U0001f1ec\U0001f1e7", "\u2764\ufe0f", "\U0001f9d1\u200d\U0001f373"],
    "rtl": ["\u0645\u0631\u062d\u0628\u0627 \u0628\u0627\u0644\u0639\u0627\u0644\u0645", "\u05e9\u05dc\u05d5\u05dd",
            "\u202egnihtemos\u202c", "\u200f\u200e\u200f", "\u0627\u0644\u062c\u0648\u0627\u0628 \u061f",
            "abc \u05d0\u05d1\u05d2 def"],
    "unicode": ["\u200b", "\ufeff", "\u200b\u200c\u200d", "Z\u0337\u0322a\u0334l\u0338g\u0336o\u0335",
                "\uff58\uff59\uff5a", "\u2126\u212b", "\ud7ff", "\U0010ffff", "\u0301\u0301\u0301"],
    "markup": ["<b>bold</b>", "<script>alert(1)</script>", "[bold]x[/bold]", "**x**", "&amp;&lt;", "<!-- -->",
               "]]>", "{{7*7}}", "${7*7}", "<img src=x onerror=alert(2)>", "[link=file:///etc/passwd]x[/link]",
               "</td></tr></table>", "\\begin{document}"],
    "sql": ["'; DROP TABLE turns; --", "1' OR '1'='1", "DROP TABLE 3", "SELECT * FROM users WHERE id = 2",
            "Robert'); DROP TABLE students;--", "UNION SELECT 4, 5", "admin'--", "\" OR \"\"=\""],
    "shell": ["$(reboot)", "`id`", "; rm -rf ~", "&& cat /etc/passwd", "| nc 127.0.0.1 4444", "$HOME", "~",
              "../../../etc/passwd", "> /dev/sda", "2>&1", ":(){ :|:& };:", "$((6*7))", "C:\\Windows\\System32"],
    "format": ["%s", "%d", "%n%n%n", "%x%x%x", "{0}", "{}", "{answer!r}", "%(turn)s", "{0.__class__}", "%1$s",
               "\\n", "%%", "%-10s|", "{:>99999}", "%.9999f"],
    "words": ["null", "undefined", "NaN", "true", "[]", "{}", "\\", "'", "\"", "asdfghjkl", "lorem ipsum dolor",
              "qwerty", "xyzzy plugh", "foo bar baz"],
}
LONG = ("x" * 301, "ab" * 2000, "z " * 1500)
WEIGHTS = {"empty": 1.0, "invalid-utf8": 1.0, "nul": 1.0, "escape": 1.0, "control": 0.6, "emoji": 1.0, "rtl": 1.0,
           "unicode": 0.8, "markup": 1.0, "sql": 1.0, "shell": 1.0, "format": 1.0, "words": 0.8, "numbers": 2.0,
           "long": 0.4, "megabyte": 0.05}


@dataclass(frozen=True)
class Question:
    """An open question as the terminal shows it."""

    turn: int
    kind: str            # "label", "demo" or "feature"
    n_objects: int = 0   # demo: the numbers run 1..n_objects
    concepts: tuple[str, ...] = ()


def _as_bytes(line) -> bytes:
    return line if isinstance(line, bytes) else line.encode("utf-8", errors="surrogatepass")


def out_of_range_numbers(question: Question, rng: np.random.Generator) -> list[str]:
    """Numbers that name nothing for this question: 0, negatives, past the end, fractions, huge."""
    top = question.n_objects if question.kind == "demo" else len(question.concepts) or 1
    if question.kind == "feature":
        return ["0", "-1", "99", "1.99", "0.0", "1..2", "9.9.9.9", f"{rng.integers(100, 10**6)}"]
    inside = int(rng.integers(1, top + 1))
    return ["0", "-1", f"-{inside}", f"{top + 1}", f"{top + int(rng.integers(2, 1000))}", "99999999999999999999",
            f"{inside}.5", "1e3", "inf", "-0", f"#{top + 1}", "\u00bd", f"{top + 1}th"]


def hostile_line(question: Question, rng: np.random.Generator) -> tuple[str, bytes]:
    """One hostile line for ``question``: its category and its bytes (no newline)."""
    names = list(WEIGHTS)
    weights = np.array([WEIGHTS[n] for n in names])
    category = names[int(rng.choice(len(names), p=weights / weights.sum()))]
    if category == "numbers":
        options = out_of_range_numbers(question, rng)
    elif category == "long":
        options = list(LONG)
    elif category == "megabyte":
        options = ["A" * MEGABYTE]
    else:
        options = STATIC[category]
    return category, _as_bytes(options[int(rng.integers(len(options)))])


def valid_answer(question: Question, rng: np.random.Generator) -> str:
    """An answer the session must accept: a concept name, an object number or 'none', a feature group."""
    if question.kind == "label":
        return question.concepts[int(rng.integers(len(question.concepts)))]
    if question.kind == "demo":
        return "none" if rng.random() < 0.1 else str(int(rng.integers(1, question.n_objects + 1)))
    return ("1", "1.1, 1.2", "all")[int(rng.integers(3))]


def typed(line: bytes) -> bytes:
    """The keystrokes that deliver ``line`` literally through a terminal: control bytes after ^V, then Enter."""
    out = bytearray()
    for byte in line:
        if byte < 0x20 or byte == 0x7F:
            out += LITERAL_NEXT
        out.append(byte)
    return bytes(out) + b"\n"
