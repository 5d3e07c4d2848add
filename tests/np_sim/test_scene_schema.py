"""The scene JSON Schema (np_sim/data/scene.schema.json) describes what `Scene.from_dict` reads: every shipped scene
passes it, structural mistakes fail both, and its fields are the loader's.

The schema is checked by a small validator written here for the keywords the schema uses (and, where the
``jsonschema`` package happens to be installed, by it as well), not by the scene loader.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from np_sim import scene as scene_module
from np_sim.benchmarks import load_benchmark
from np_sim.errors import SceneError
from np_sim.scene import Scene

REPO = Path(__file__).resolve().parents[2]
SCHEMA = json.loads((REPO / "np_sim" / "data" / "scene.schema.json").read_text())
EXAMPLE_FILES = sorted((REPO / "np_sim" / "examples").rglob("*.json"))


def _resolve(node: dict) -> dict:
    """Follow a local ``$ref`` (``#/$defs/name``)."""
    while "$ref" in node:
        node = SCHEMA["$defs"][node["$ref"].rsplit("/", 1)[1]]
    return node


def _type_ok(value, kind: str) -> bool:
    checks = {"object": lambda v: isinstance(v, dict), "array": lambda v: isinstance(v, list),
              "string": lambda v: isinstance(v, str),
              "number": lambda v: isinstance(v, (int, float)) and not isinstance(v, bool),
              "integer": lambda v: isinstance(v, int) and not isinstance(v, bool)}
    return checks[kind](value)


def errors(value, node: dict = SCHEMA, where: str = "$") -> list[str]:
    """Every violation of ``node`` by ``value`` (keywords: type, const, required, properties,
    additionalProperties, items, minItems, maxItems, oneOf, $ref)."""
    node = _resolve(node)
    kinds = node.get("type")
    if kinds is not None and not any(_type_ok(value, k) for k in ([kinds] if isinstance(kinds, str) else kinds)):
        return [f"{where}: expected {kinds}"]
    if "const" in node and not (value == node["const"] and type(value) is type(node["const"])):
        return [f"{where}: expected {node['const']!r}"]
    found = []
    if "oneOf" in node:
        matching = sum(not errors(value, option, where) for option in node["oneOf"])
        if matching != 1:
            found.append(f"{where}: matches {matching} of the oneOf options")
    if isinstance(value, dict):
        found += [f"{where}.{key}: required" for key in node.get("required", ()) if key not in value]
        for key, item in value.items():
            if key in node.get("properties", {}):
                found += errors(item, node["properties"][key], f"{where}.{key}")
            elif node.get("additionalProperties") is False:
                found.append(f"{where}.{key}: not allowed")
            elif isinstance(node.get("additionalProperties"), dict):
                found += errors(item, node["additionalProperties"], f"{where}.{key}")
    if isinstance(value, list):
        if len(value) < node.get("minItems", 0) or len(value) > node.get("maxItems", len(value)):
            found.append(f"{where}: {len(value)} items")
        if "items" in node:
            for i, item in enumerate(value):
                found += errors(item, node["items"], f"{where}[{i}]")
    return found


def _both(document) -> list[str]:
    """This module's verdict, cross-checked with ``jsonschema`` when that package is importable."""
    found = errors(document)
    try:
        import jsonschema
    except ImportError:
        return found
    assert (not found) == jsonschema.Draft202012Validator(SCHEMA).is_valid(document), found
    return found


def test_the_schema_lists_exactly_the_fields_the_loader_reads():
    assert set(SCHEMA["properties"]) == set(scene_module._TOP_LEVEL_KEYS)
    assert set(SCHEMA["required"]) == set(scene_module._REQUIRED_KEYS)


@pytest.mark.parametrize("path", EXAMPLE_FILES, ids=lambda p: p.stem)
def test_every_shipped_example_scene_passes_the_schema(path):
    assert EXAMPLE_FILES and not _both(json.loads(path.read_text()))
    Scene.load(path)


def test_the_benchmark_scenes_written_as_json_pass_the_schema():
    for scene in load_benchmark("factorial", "test")[:5] + load_benchmark("topology", "test")[:3]:
        assert not _both(scene.to_dict())


GOOD = {"boundary": [[0, 0], [20, 0], [20, 20], [0, 20]], "obstacles": [{"circle": [15, 15, 1]}],
        "target": [5.0, 5.0, 0.0], "start_region": {"box": [10, 2, 18, 8]}, "start_headings": [-0.5, 0.5],
        "starts": [[12.0, 12.0, 1.0]]}


def test_the_optional_start_fields_pass_and_load():
    assert not _both(GOOD)
    Scene.from_dict(GOOD)


@pytest.mark.parametrize("change", [
    {"target": [1.0, 2.0]},                                 # a pose needs three numbers
    {"starts": [[1.0, 2.0, "north"]]},                      # numbers only
    {"start_headings": [0.0]},                              # a range is two numbers
    {"start_region": {"box": [1, 2, 3]}},                   # a box is four numbers
    {"start_region": {"polygon": [[0, 0], [1, 0], [1, 1]]}},  # the region is a point list or a box
    {"obstacles": [{"polygon": [[0, 0], [1, 0], [1, 1]], "circle": [0, 0, 1]}]},  # one kind per obstacle
    {"obstacles": [{"circle": [0, 0, True]}]},              # booleans are not numbers
    {"version": 2},
    {"tags": {"split": ["a"]}},
    {"start_pose": [1, 2, 3]},                              # unknown field
])
def test_structural_mistakes_fail_the_schema_and_the_loader(change):
    document = {**GOOD, **change}
    assert _both(document)
    with pytest.raises(SceneError):
        Scene.from_dict(document)
