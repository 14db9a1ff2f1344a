"""Changing scene keys by dotted path, before validation.

A key path names a value of the scene's TOML document: ``duration``,
``solver.rtol``, ``trajectory.period``, ``materials.steel.youngs_modulus``.
Entries of the ``[[clearance]]`` array are addressed by their ``joint`` name
(``clearance.R1.radial_clearance``, ``clearance.S1.friction.dynamic``) or by
their index (``clearance.0.restitution``); ``[[force]]`` entries by their ``name``
(``force.tip_spring.stiffness``). Setting a key that the scene does not
have yet creates it (the validation that follows rejects keys that do not
exist in the schema, naming them); a path through a value that is not a table
is refused here, naming the path.

Used by :func:`robot.scene.loader.load_scene` (``overrides=``), the Python API
and the sweep tool, so that a change from Python is validated exactly as the
same change written in the file.
"""

from __future__ import annotations

import copy
from typing import Any, Mapping

from robot.errors import SceneError

#: arrays of tables whose entries are addressed by this key (or by index)
ARRAY_ENTRY_KEYS = {"clearance": "joint", "force": "name"}
#: keys that choose what kind a table is (a time function, an actuator mode, a friction law): the other keys of
#: one kind do not fit another, so a table given another kind starts afresh (``extends`` and overrides alike)
KIND_KEYS = ("function", "mode", "law")


def _array_entry(entries: list, name: str, path: str, array: str) -> dict:
    key = ARRAY_ENTRY_KEYS[array]
    for entry in entries:
        if isinstance(entry, dict) and entry.get(key) == name:
            return entry
    if name.isdigit() and int(name) < len(entries):
        return entries[int(name)]
    names = [e.get(key) for e in entries if isinstance(e, dict)]
    raise SceneError(
        f"override {path!r}: the scene has no [[{array}]] entry with {key} = {name!r}; entries: {names}",
        key=path,
        value=name,
    )


def _container(document: dict, parts: list[str], path: str) -> dict:
    """The table that holds the last part of ``parts`` (tables on the way are created)."""
    node = document
    i = 0
    while i < len(parts) - 1:
        part = parts[i]
        child = node.get(part)
        if isinstance(child, list) and part in ARRAY_ENTRY_KEYS:
            if i + 1 >= len(parts) - 1:
                raise SceneError(f"override {path!r} names a whole [[{part}]] entry; name one of its keys", key=path, value=None)
            node = _array_entry(child, parts[i + 1], path, part)
            i += 2
            continue
        if child is None:
            child = node.setdefault(part, {})
        if not isinstance(child, dict):
            where = ".".join(parts[: i + 1])
            raise SceneError(f"override {path!r}: {where} is {child!r}, not a table", key=path, value=child)
        node = child
        i += 1
    return node


def document_value(document: Mapping[str, Any], path: str) -> Any:
    """The value at key path ``path`` of a scene document (``[[clearance]]`` entries by joint name or index).

    SceneError naming the path if the document has no such key.
    """
    node: Any = document
    parts = path.split(".")
    i = 0
    while i < len(parts):
        part = parts[i]
        if not isinstance(node, dict) or part not in node:
            raise SceneError(f"key path {path!r}: the scene has no key {'.'.join(parts[: i + 1])!r}", key=path, value=None)
        node = node[part]
        if isinstance(node, list) and part in ARRAY_ENTRY_KEYS and i + 1 < len(parts):
            node = _array_entry(node, parts[i + 1], path, part)
            i += 1
        i += 1
    return node


def apply_overrides(document: Mapping[str, Any], overrides: Mapping[str, Any]) -> dict:
    """Return a deep copy of ``document`` with each ``path -> value`` of ``overrides`` set.

    A path ending in a :data:`KIND_KEYS` key that changes the table's kind (``friction.law = "none"`` over a
    Brown-McPhee table) empties the table first, as ``extends`` replaces such a table whole: the new table is
    the keys given in this call (``friction.coefficient`` with ``friction.law = "coulomb"``; an actuator's
    ``mode`` with its new ``function``), in any order. A table is emptied at most once per call.
    """
    result = copy.deepcopy(dict(document))
    for path in overrides:
        if not isinstance(path, str) or not path or any(not part for part in path.split(".")):
            raise SceneError(f"override key path {path!r} must be dotted names such as 'solver.rtol'", key=str(path), value=overrides[path])
    emptied: set[int] = set()
    for path, value in sorted(overrides.items(), key=lambda item: item[0].split(".")[-1] not in KIND_KEYS):
        parts = path.split(".")
        table = _container(result, parts, path)
        if parts[-1] in KIND_KEYS and table.get(parts[-1]) != value and id(table) not in emptied:
            table.clear()  # another kind: the old kind's keys do not carry over
            emptied.add(id(table))
        table[parts[-1]] = copy.deepcopy(value)
    return result
