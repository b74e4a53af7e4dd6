"""YAML read with bounded work: aliases may not expand a document beyond a file's size.

PyYAML's safe_load builds an alias (``*a``) as a second reference to the anchored value,
so nine levels of nine aliases each load in microseconds as 9**9 references; whatever then
walks the value (a check, an error message's repr, a JSON dump) does 387 million steps.
:func:`load_yaml` composes the document's node graph first and refuses it, before any value
is built, when its size with every alias expanded exceeds MAX_EXPANDED (or an alias refers
to a node that contains it: a recursive document).
"""
from typing import Any

import yaml

# units of expanded size: 1 per node plus the characters of each scalar.  A document
# without aliases costs at most about as many units as its text has characters (each node
# takes at least one character of text), so twice the sweep-file limit
# (gpme_io.input_files.SWEEP_FILE_LIMIT, 1 MB) never refuses a file that uses no aliases.
MAX_EXPANDED = 2_000_000


class YamlSizeError(ValueError):
    """A YAML document expands (through its aliases) beyond MAX_EXPANDED, or is recursive."""


def _children(node) -> list:
    if isinstance(node, yaml.SequenceNode):
        return list(node.value)
    if isinstance(node, yaml.MappingNode):
        return [n for pair in node.value for n in pair]
    return []


def _own_size(node) -> int:
    return 1 + (len(node.value) if isinstance(node, yaml.ScalarNode) else 0)


def expanded_size(root, limit: int = MAX_EXPANDED) -> int:
    """Size (nodes + scalar characters) of the node graph ``root`` with every alias
    expanded; YamlSizeError as soon as it exceeds ``limit`` or a node contains itself.
    Each distinct node is visited once (shared nodes are counted by multiplication)."""
    sizes = {}                   # id(node) -> expanded size
    open_nodes = set()           # ids of the nodes on the path from the root
    stack = [(root, False)]
    while stack:
        node, leaving = stack.pop()
        key = id(node)
        if leaving:
            open_nodes.discard(key)
            size = _own_size(node) + sum(sizes[id(c)] for c in _children(node))
            if size > limit:
                raise YamlSizeError(
                    f"its aliases expand it to more than {limit} nodes and characters "
                    f"(line {node.start_mark.line + 1}); a sweep file this large is an alias "
                    "bomb, not a sweep: write the values out, or use fewer levels of aliases")
            sizes[key] = size
            continue
        if key in sizes:
            continue
        open_nodes.add(key)
        stack.append((node, True))
        for child in _children(node):
            if id(child) in open_nodes:
                raise YamlSizeError(
                    f"an alias at line {child.start_mark.line + 1} refers to a value that "
                    "contains it (a recursive document has no end); anchor (&) a value and "
                    "refer (*) to it only outside it")
            if id(child) not in sizes:
                stack.append((child, False))
    return sizes[id(root)]


def load_yaml(text: str, limit: int = MAX_EXPANDED) -> Any:
    """The value of the YAML document ``text`` (safe tags only, as yaml.safe_load), after
    :func:`expanded_size` has bounded it; None for an empty document.  Raises
    YamlSizeError, or yaml.YAMLError for malformed text."""
    loader = yaml.SafeLoader(text)
    try:
        node = loader.get_single_node()
        if node is None:
            return None
        expanded_size(node, limit)
        return loader.construct_document(node)
    finally:
        loader.dispose()
