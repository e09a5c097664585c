"""The feature hierarchy as a numbered tree for the feature-subset question (thesis §5.4.1, §6.3.1).

The teacher answers with tree numbers ("1.1, 1.2.3"), ranges ("1.1-1.3"),
feature or group names ("colour, size"), or "all". A leading "ignore" (or
"without", "except", ...) names the features to leave out (human feature
removal, HFR) instead of the ones to use (human feature selection, HFS).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

from dialog.parsing import Reading
from dialog.vocabulary import MAX_ANSWER_CHARS, Vocabulary, clean, load_vocabulary, phrase, refused_characters, word_key

_NUMBER = re.compile(r"^\d{1,3}(\.\d{1,3})*$")
_PLAIN_WORDS = ("feature", "features", "group", "groups")
_RANGE = re.compile(r"^(\d{1,3}(?:\.\d{1,3})*)-(\d{1,3}(?:\.\d{1,3})*)$")


@dataclass
class TreeNode:
    """A group (``feature`` is None) or one feature (its column index), with its tree number."""

    number: str
    name: str
    description: str = ""
    feature: int | None = None
    children: list[TreeNode] = field(default_factory=list)

    def leaves(self) -> list[int]:
        if self.feature is not None:
            return [self.feature]
        return [index for child in self.children for index in child.leaves()]


def feature_groups(feature_names) -> list[tuple[str, str]]:
    """(group path, description) of every feature; names outside the catalogue go under "other"."""
    from bullet_world.features import feature_info

    names = list(feature_names)
    try:
        infos = feature_info(names)
    except KeyError:
        infos = []
        for name in names:
            try:
                infos.append(feature_info([name])[0])
            except KeyError:
                infos.append(None)
    return [(info.group, info.description) if info else ("other", "") for info in infos]


class FeatureTree:
    """Numbered groups and features of one feature list, in column order."""

    def __init__(self, feature_names, groups: list[tuple[str, str]] | None = None):
        self.feature_names = tuple(feature_names)
        groups = groups if groups is not None else feature_groups(self.feature_names)
        self.roots: list[TreeNode] = []
        self.by_number: dict[str, TreeNode] = {}
        for index, (name, (group, description)) in enumerate(zip(self.feature_names, groups)):
            siblings, prefix = self.roots, ""
            for part in [p for p in group.split("/") if p]:
                node = next((n for n in siblings if n.feature is None and n.name == part), None)
                if node is None:
                    node = TreeNode(f"{prefix}{len(siblings) + 1}", part)
                    siblings.append(node)
                    self.by_number[node.number] = node
                siblings, prefix = node.children, f"{node.number}."
            leaf = TreeNode(f"{prefix}{len(siblings) + 1}", name, description, index)
            siblings.append(leaf)
            self.by_number[leaf.number] = leaf

    def lines(self) -> list[str]:
        """The tree as indented, numbered lines (groups, then each feature with its description)."""
        out: list[str] = []

        def walk(nodes, depth):
            for node in nodes:
                text = f"{'  ' * depth}{node.number} {node.name}"
                if node.feature is not None and node.description:
                    text += f": {node.description}"
                out.append(text)
                walk(node.children, depth + 1)

        walk(self.roots, 0)
        return out

    def nodes(self):
        return self.by_number.values()

    def group_of(self, index: int) -> str:
        """The slash-separated group path of feature ``index``."""
        number = next(n.number for n in self.nodes() if n.feature == index)
        parts, path = number.split("."), []
        for depth in range(1, len(parts)):
            path.append(self.by_number[".".join(parts[:depth])].name)
        return "/".join(path)

    def numbers_for(self, indices) -> list[str]:
        """The fewest tree numbers that select exactly ``indices`` (whole groups where possible)."""
        wanted = set(int(i) for i in indices)
        chosen: list[str] = []

        def walk(nodes):
            for node in nodes:
                leaves = set(node.leaves())
                if leaves and leaves <= wanted:
                    chosen.append(node.number)
                elif leaves & wanted:
                    walk(node.children)

        walk(self.roots)
        return chosen

    # -- reading an answer ------------------------------------------------------------
    def _by_name(self, key: str) -> list[TreeNode]:
        return [n for n in self.nodes() if clean(n.name) == key or phrase(n.name) == key]

    def _range(self, start: str, end: str) -> list[TreeNode] | None:
        first, last = start.split("."), end.split(".")
        if len(first) != len(last) or first[:-1] != last[:-1] or int(first[-1]) > int(last[-1]):
            return None
        if start not in self.by_number or end not in self.by_number:  # both ends must be in the tree
            return None
        prefix = ".".join(first[:-1])
        numbers = [f"{prefix}.{k}" if prefix else str(k) for k in range(int(first[-1]), int(last[-1]) + 1)]
        return [self.by_number[n] for n in numbers if n in self.by_number] or None

    def read(self, text: str, vocabulary: Vocabulary | None = None) -> Reading:
        """Feature indices to use, from an HFS or HFR answer; unknown items are named, never guessed."""
        vocabulary = vocabulary or load_vocabulary()
        accepted = ("Give the numbers of the groups or features to use (for example '1.1, 1.2' or '1.1-1.3'), "
                    "their names, or 'all'; start with 'ignore' to name the ones to leave out instead; or say "
                    "'don't know', 'skip', 'why', 'undo', 'help' or 'quit'.")
        if len(text) > MAX_ANSWER_CHARS:
            return Reading("unreadable", message=f"That answer is too long ({len(text)} characters; at most "
                                                 f"{MAX_ANSWER_CHARS}). {accepted}")
        odd = refused_characters(text)
        if odd:
            return Reading("unreadable", message=f"That answer holds {odd}; please type plain text. {accepted}")
        command = vocabulary.command(text)
        if command:
            return Reading(command)
        body = clean(text)
        if not body:
            return Reading("unreadable", message=f"I got an empty answer. {accepted}")
        mode = "use"
        for word in vocabulary.ignore_words:
            if body == word or body.startswith(word + " ") or body.startswith(word + ":"):
                mode, body = "ignore", body[len(word):]
                break
        else:
            for word in vocabulary.use_words:
                if body.startswith(word + " ") or body.startswith(word + ":"):
                    body = body[len(word):]
                    break
        items = [item.strip(" .:") for item in re.split(r"[,;]|\s+and\s+|\s+", body.replace(" - ", "-"))]
        items = [item for item in items if item]
        selected: set[int] = set()
        unknown: list[str] = []
        if word_key(body) in vocabulary.all_words:
            selected = set(range(len(self.feature_names)))
            items = []
        for item in items:
            range_match = _RANGE.match(item)
            if _NUMBER.match(item) and item in self.by_number:
                nodes = [self.by_number[item]]
            elif range_match:
                nodes = self._range(*range_match.groups())
            else:
                nodes = self._by_name(item) or None
            if nodes is None:
                if word_key(item) in vocabulary.fillers or word_key(item) in _PLAIN_WORDS:
                    continue
                unknown.append(item[:30])
                continue
            for node in nodes:
                selected.update(node.leaves())
        if unknown:
            numbered = (f" (the groups are numbered 1 to {len(self.roots)}, as listed)"
                        if any(ch.isdigit() for u in unknown for ch in u) else "")
            return Reading("unreadable", message=f"I don't know {', '.join(repr(u) for u in unknown[:5])} in the "
                                                 f"feature list{numbered}. {accepted}")
        if not selected:
            return Reading("unreadable", message=f"That names no feature. {accepted}")
        if mode == "ignore":
            selected = set(range(len(self.feature_names))) - selected
            if not selected:
                return Reading("unreadable", message=f"That would leave no feature to use. {accepted}")
        return Reading("answer", tuple(sorted(selected)), message=f"mode={mode}")
