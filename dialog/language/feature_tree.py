"""The feature hierarchy as a numbered tree for the feature-subset question (thesis §5.4.1, §6.3.1).

The teacher answers with tree numbers ("1.1, 1.2.3"), ranges ("1.1-1.3"),
feature or group names ("colour, size"), or "all". A leading "ignore" (or
"without", "except", ...) names the features to leave out (human feature
removal, HFR) instead of the ones to use (human feature selection, HFS).

A tree longer than a screen is shown as its groups first (``overview``);
"more 1.2" (or, then, a group's bare name) opens one group: a reply that lists
its features, not an answer.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

from dialog.language.parsing import Reading
from dialog.language.vocabulary import (
    MAX_ANSWER_CHARS,
    Vocabulary,
    clean,
    load_vocabulary,
    phrase,
    refused_characters,
    word_key,
)

_NUMBER = re.compile(r"^\d{1,3}(\.\d{1,3})*$")
_PLAIN_WORDS = ("feature", "features", "group", "groups")
_OPEN_WORDS = ("more", "open", "expand")
OVERVIEW_LINES = 20  # the feature question's list stays within this many lines
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
        return _tree_lines(self.roots, 0)

    def nodes(self):
        return self.by_number.values()

    @property
    def collapsed(self) -> bool:
        """Whether the whole tree is too long for the question, which then lists the groups first."""
        return len(self.lines()) > OVERVIEW_LINES

    def overview(self, max_lines: int = OVERVIEW_LINES) -> list[str]:
        """At most ``max_lines`` lines: the whole tree if it fits, else its groups as deep as fit, with counts."""
        if len(self.lines()) <= max_lines:
            return self.lines()
        hint = "(say 'more 1.2' or a group's name to list its features; answer with numbers or names)"
        levels: dict[int, list[TreeNode]] = {}

        def walk(nodes, depth):
            for node in nodes:
                if node.feature is None or depth == 0:
                    levels.setdefault(depth, []).append(node)
                    walk(node.children, depth + 1)

        walk(self.roots, 0)
        depth, shown = 0, len(levels.get(0, []))
        while depth + 1 in levels and shown + len(levels[depth + 1]) <= max_lines - 1:
            depth, shown = depth + 1, shown + len(levels[depth + 1])
        out: list[str] = []

        def show(nodes, level):
            for node in nodes:
                if len(out) >= max_lines - 2:
                    return
                if node.feature is not None:
                    if level == 0:
                        out.append(f"{node.number} {node.name}: {node.description}".rstrip(": "))
                    continue
                count = len(node.leaves())
                text = f"{'  ' * level}{node.number} {node.name}: {count} feature{'s' * (count != 1)}"
                if level == depth or not any(child.feature is None for child in node.children):
                    text += f" ({_sample(self.feature_names[i] for i in node.leaves())})"
                    out.append(text)
                else:
                    out.append(text)
                    show(node.children, level + 1)

        show(self.roots, 0)
        return [*out, hint]

    def opened(self, node: TreeNode) -> list[str]:
        """The lines that open one group: its features (and subgroups) with their descriptions."""
        if node.feature is not None:
            return [f"{node.number} {node.name}: {node.description}".rstrip(": ")]
        count = len(node.leaves())
        lines = [f"{node.number} {node.name}, {count} feature{'s' * (count != 1)} (say '{node.number}' to use "
                 f"all of them):"]
        lines += _tree_lines(node.children, 1)
        if len(lines) <= 2 * OVERVIEW_LINES or not any(child.feature is None for child in node.children):
            return lines
        lines = lines[:1]  # too long for a screen: its subgroups, each to be opened in turn
        for child in node.children:
            if child.feature is not None:
                lines.append(f"  {child.number} {child.name}: {child.description}".rstrip(": "))
            else:
                count = len(child.leaves())
                lines.append(f"  {child.number} {child.name}: {count} feature{'s' * (count != 1)} "
                             f"({_sample(self.feature_names[i] for i in child.leaves())})")
        first = next(child.number for child in node.children if child.feature is None)
        return [*lines, f"(say 'more {first}' to list one of them)"]

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

    def _open(self, body: str, accepted: str) -> Reading | None:
        """A "more N" line (or, in a collapsed tree, a bare group name) as a group to list; None for other lines."""
        target, asked = body.strip(" .:"), False
        for word in _OPEN_WORDS:
            if target == word or target.startswith(word + " "):
                target, asked = target[len(word):].strip(" .:"), True
                for lead in ("group ", "the "):
                    target = target[len(lead):] if target.startswith(lead) else target
                break
        if _NUMBER.match(target) and target in self.by_number:
            nodes = [self.by_number[target]] if asked else []
        else:
            nodes = self._by_name(target)
            if not asked and (not self.collapsed or any(node.feature is not None for node in nodes)):
                nodes = []  # a feature's name, or a name in a tree shown whole, chooses
        if nodes:
            lines = [line for node in nodes for line in self.opened(node)]
            return Reading("more", tuple(node.number for node in nodes), message="\n".join(lines))
        if asked:
            shown = f" {target[:30]!r}" if target else ""
            return Reading("unreadable", message=f"I can't open{shown}: say 'more' and the number (1 to "
                                                 f"{len(self.roots)}, 1.1, ...) or name of a group. {accepted}")
        return None

    def read(self, text: str, vocabulary: Vocabulary | None = None) -> Reading:
        """Feature indices to use, from an HFS or HFR answer; unknown items are named, never guessed.

        "more N" (and, in a collapsed tree, a group's bare name) reads as kind "more": the group's lines.
        """
        vocabulary = vocabulary or load_vocabulary()
        accepted = ("Give the numbers of the groups or features to use (for example '1.1, 1.2' or '1.1-1.3'), "
                    "their names, or 'all'; start with 'ignore' to name the ones to leave out instead; say "
                    "'more 1.2' to list a group's features; or say 'don't know', 'skip', 'why', 'undo', 'help' or "
                    "'quit'.")
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
        opened = self._open(body, accepted)
        if opened is not None:
            return opened
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


def _sample(names, limit: int = 60) -> str:
    """Feature names joined up to about ``limit`` characters, then "..."."""
    out, used = [], 0
    for name in names:
        if out and used + len(name) + 2 > limit:
            return ", ".join(out) + ", ..."
        out.append(name)
        used += len(name) + 2
    return ", ".join(out)


def _tree_lines(nodes, depth: int) -> list[str]:
    """One indented line per node and its descendants: number, name, and a feature's description."""
    lines: list[str] = []
    for node in nodes:
        text = f"{'  ' * depth}{node.number} {node.name}"
        if node.feature is not None and node.description:
            text += f": {node.description}"
        lines.append(text)
        lines += _tree_lines(node.children, depth + 1)
    return lines
