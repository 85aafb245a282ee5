"""A YAML reader for params.yaml that refuses a key given twice in one mapping.

PyYAML's ``safe_load`` keeps the last of two equal keys without a word, so a value edited in one place and left
in another would silently win or lose. :func:`read_yaml` composes the document, checks every mapping at every
depth for a repeated key (naming its key path and both line numbers), then constructs it like ``safe_load``.
"""

from __future__ import annotations

from typing import IO, Any

import yaml

#: YAML's merge key ``<<``, which may legitimately appear more than once
_MERGE_TAG = "tag:yaml.org,2002:merge"


class DuplicateKeyError(ValueError):
    """Keys given twice in one mapping; :attr:`duplicates` lists ``(key path, first line, second line)``."""

    def __init__(self, source: str, duplicates: list[tuple[str, int, int]]) -> None:
        self.duplicates = duplicates
        lines = [
            f"{source}: duplicated key {path} at line {second} (first at line {first}): YAML keeps only the last, "
            "remove one"
            for path, first, second in duplicates
        ]
        super().__init__("\n".join(lines))


def _join(path: str, key: Any) -> str:
    return f"{path}.{key}" if path else str(key)


def _duplicates(loader: yaml.SafeLoader, node: yaml.Node, path: str, seen: set[int]) -> list[tuple[str, int, int]]:
    """Every repeated key in ``node`` and below it: (key path, first line, repeated line), lines from 1."""
    if id(node) in seen:  # an alias of a node already checked
        return []
    seen.add(id(node))
    found: list[tuple[str, int, int]] = []
    if isinstance(node, yaml.SequenceNode):
        for i, item in enumerate(node.value):
            found += _duplicates(loader, item, f"{path}[{i}]", seen)
    elif isinstance(node, yaml.MappingNode):
        first_line: dict[Any, int] = {}
        for key_node, value_node in node.value:
            if key_node.tag == _MERGE_TAG:
                continue
            key = loader.construct_object(key_node, deep=True)
            try:
                hash(key)
            except TypeError:  # a mapping or list as a key: the constructor reports it
                continue
            line = key_node.start_mark.line + 1
            if key in first_line:
                found.append((_join(path, key), first_line[key], line))
            else:
                first_line[key] = line
            found += _duplicates(loader, value_node, _join(path, key), seen)
    return found


def read_yaml(stream: str | IO[str], source: str = "params.yaml") -> Any:
    """The one document of ``stream`` as Python objects, like :func:`yaml.safe_load`, refusing repeated keys.

    Parameters
    ----------
    stream
        The YAML text or an open text file.
    source
        Name of the file, for the message.

    Returns
    -------
    Any
        The document (None for an empty one).

    Raises
    ------
    DuplicateKeyError
        If a mapping at any depth gives a key twice; every such key is listed, each with both line numbers.
    yaml.YAMLError
        If the text is not valid YAML.
    """
    loader = yaml.SafeLoader(stream)
    try:
        node = loader.get_single_node()
        if node is None:
            return None
        duplicates = sorted(_duplicates(loader, node, "", set()), key=lambda d: d[2])
        if duplicates:
            raise DuplicateKeyError(source, duplicates)
        return loader.construct_document(node)
    finally:
        loader.dispose()
