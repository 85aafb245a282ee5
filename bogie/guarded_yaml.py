"""A YAML reader for the files a user writes (params.yaml, bogie files) that refuses what would hang, exhaust memory
or silently drop a value.

It refuses a key given twice in one mapping.

PyYAML's ``safe_load`` keeps the last of two equal keys without a word, so a value edited in one place and left
in another would silently win or lose. :func:`read_yaml` composes the document, checks every mapping at every
depth for a repeated key (naming its key path and both line numbers), then constructs it like ``safe_load``.

A document too large to be a parameter file is refused before it is built, in bounded time and memory
(:class:`DocumentTooLargeError`): nesting deeper than :data:`MAX_DEPTH` (PyYAML composes recursively, 5,000 nested
``[`` raised a RecursionError), or more than :data:`MAX_NODES` values once every alias is expanded (a "billion laughs"
of nested aliases is a few lines that expand to 10^9 values, which validation and its message would walk), or an
integer of more than :data:`MAX_INT_DIGITS` digits (a 401-digit integer overflowed the conversion to a float).
:func:`read_yaml_file` reads only a regular file of at most :data:`MAX_FILE_BYTES` (a FIFO waited for ever, /dev/zero
filled the memory).

params.yaml (``pipeline.config``) and bogie files (``bogie.bogie_file``) are both read through it.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import IO, Any

import yaml

from bogie.files import regular_file

#: YAML's merge key ``<<``, which may legitimately appear more than once
_MERGE_TAG = "tag:yaml.org,2002:merge"

#: the deepest nesting of mappings and lists a parameter file may have (params.yaml nests 4 deep) [-]
MAX_DEPTH = 32
#: the most values (scalars, lists, mappings) a parameter file may hold, aliases expanded (params.yaml: about 400) [-]
MAX_NODES = 100_000
#: the most digits an integer may have [-]: a count or a seed fits in 20 (2^64 has 20); more is a typo (a convention)
MAX_INT_DIGITS = 20
#: the largest file read [bytes]: 1 MiB, about 90 times params.yaml (11 KiB; a bogie file is 2 KiB): a convention
MAX_FILE_BYTES = 2**20


class DocumentTooLargeError(ValueError):
    """A YAML document nested too deep or too large once its aliases are expanded: refused before it is built."""


class _Loader(yaml.SafeLoader):
    """PyYAML's safe loader that refuses nesting deeper than :data:`MAX_DEPTH` while it composes."""

    def __init__(self, stream: str | IO[str], source: str) -> None:
        super().__init__(stream)
        self.source, self.depth = source, 0

    def compose_node(self, parent: yaml.Node | None, index: Any) -> yaml.Node | None:
        self.depth += 1
        try:
            if self.depth > MAX_DEPTH:
                line = self.peek_event().start_mark.line + 1
                raise DocumentTooLargeError(
                    f"{self.source}: nested more than {MAX_DEPTH} levels deep at line {line}: not a parameter file"
                )
            return super().compose_node(parent, index)
        finally:
            self.depth -= 1

    def construct_yaml_int(self, node: yaml.ScalarNode) -> int:
        digits = sum(c.isdigit() for c in str(node.value))
        if digits > MAX_INT_DIGITS:
            raise DocumentTooLargeError(
                f"{self.source}: an integer of {digits} digits at line {node.start_mark.line + 1}: at most "
                f"{MAX_INT_DIGITS} digits; a number that large is a typo"
            )
        return super().construct_yaml_int(node)


_Loader.add_constructor("tag:yaml.org,2002:int", _Loader.construct_yaml_int)


def _expanded_size(node: yaml.Node, sizes: dict[int, int]) -> int:
    """The number of values under ``node`` with every alias expanded, each shared node counted once (memoised)."""
    if id(node) not in sizes:
        children: list[yaml.Node] = []
        if isinstance(node, yaml.SequenceNode):
            children = node.value
        elif isinstance(node, yaml.MappingNode):
            children = [n for pair in node.value for n in pair]
        sizes[id(node)] = min(1 + sum(_expanded_size(c, sizes) for c in children), MAX_NODES + 1)
    return sizes[id(node)]


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
    DocumentTooLargeError
        If the document nests deeper than :data:`MAX_DEPTH` or holds more than :data:`MAX_NODES` values.
    yaml.YAMLError
        If the text is not valid YAML.
    """
    loader = _Loader(stream, source)
    try:
        node = loader.get_single_node()
        if node is None:
            return None
        size = _expanded_size(node, {})
        if size > MAX_NODES:
            raise DocumentTooLargeError(
                f"{source}: more than {MAX_NODES:,} values once its aliases are expanded (an alias of an alias of "
                "...): not a parameter file; write the values out"
            )
        duplicates = sorted(_duplicates(loader, node, "", set()), key=lambda d: d[2])
        if duplicates:
            raise DuplicateKeyError(source, duplicates)
        return loader.construct_document(node)
    finally:
        loader.dispose()


def read_text_file(path: str | os.PathLike[str], max_bytes: int = MAX_FILE_BYTES) -> str:
    """The UTF-8 text of a regular file of at most ``max_bytes`` bytes; a FIFO, a device, a folder or a larger file
    is refused before it is read.

    Raises
    ------
    DocumentTooLargeError
        A file larger than ``max_bytes``.
    ValueError
        Not a regular file (symlinks followed).
    OSError, UnicodeDecodeError
        The file cannot be read, or is not UTF-8.
    """
    path = Path(path)
    regular_file(path)
    with open(path, "rb") as fh:
        data = fh.read(max_bytes + 1)
    if len(data) > max_bytes:
        raise DocumentTooLargeError(f"{path}: more than {max_bytes:,} bytes: not a parameter or bogie file")
    return data.decode("utf-8")


def read_yaml_file(path: str | os.PathLike[str], source: str | None = None) -> Any:
    """:func:`read_yaml` of the file ``path`` (:func:`read_text_file`: a regular file of at most
    :data:`MAX_FILE_BYTES`)."""
    return read_yaml(read_text_file(path), str(path) if source is None else source)
