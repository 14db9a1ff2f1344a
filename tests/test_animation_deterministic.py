"""Static HTML animations are deterministic: the same result gives byte-identical files.

meshcat names every scene element with a time-based ``uuid.uuid1()``; the
static-page recorder (robot.viz.animation._SceneRecorder) replaces those UUIDs by
ones derived from the scene path, one-to-one, so sharing and distinctness of
elements (what three.js draws) are unchanged.
"""

from __future__ import annotations

import base64
import re
from pathlib import Path

import pytest
import umsgpack

from robot.io.results import save_result
from robot.viz.animation import _SceneRecorder, _meshcat, export_html

UUID = re.compile(r"^[0-9a-f]{8}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{12}$")


def commands(page: str) -> list[dict]:
    return [umsgpack.unpackb(base64.b64decode(b)) for b in re.findall(r'meshcatCommand\("([A-Za-z0-9+/=]+)"\)', page)]


def uuid_strings(value) -> list[str]:
    """Every UUID-shaped string in a decoded command, in a fixed walk order (definitions and references)."""
    if isinstance(value, dict):
        return [s for item in value.values() for s in uuid_strings(item)]
    if isinstance(value, list):
        return [s for item in value for s in uuid_strings(item)]
    return [value] if isinstance(value, str) and UUID.match(value) else []


def uuid_pattern(page: str) -> list[int]:
    """Each UUID occurrence replaced by the index of its first occurrence: which elements are shared or distinct."""
    first: dict[str, int] = {}
    return [first.setdefault(s, len(first)) for c in commands(page) for s in uuid_strings(c)]


def masked(page: str) -> list:
    def mask(value):
        if isinstance(value, dict):
            return {k: mask(v) for k, v in value.items()}
        if isinstance(value, list):
            return [mask(v) for v in value]
        return "<uuid>" if isinstance(value, str) and UUID.match(value) else value

    return [mask(c) for c in commands(page)]


@pytest.fixture(scope="module")
def spherical_result(tmp_path_factory) -> Path:
    from robot.run import build_run, run_scene

    result = run_scene(build_run("spherical", duration=0.02))
    return save_result(result, tmp_path_factory.mktemp("results") / "spherical.npz")


def test_same_result_gives_byte_identical_html(spherical_result, tmp_path, monkeypatch):
    options = dict(speed=0.02, exaggerate=100)
    first = export_html(spherical_result, tmp_path / "a.html", **options).html_path.read_bytes()
    second = export_html(spherical_result, tmp_path / "b.html", **options).html_path.read_bytes()
    assert first == second
    page = first.decode("utf-8")
    pattern = uuid_pattern(page)
    assert len(set(pattern)) > 10  # links, clearance elements, arrows, trails: each with object, geometry and material

    # meshcat's own (time-based) UUIDs: same scene, same number of distinct elements, same sharing
    monkeypatch.setattr(_SceneRecorder, "_stable_uuids", lambda self, data: None)
    raw = export_html(spherical_result, tmp_path / "raw.html", **options).html_path.read_text(encoding="utf-8")
    assert raw != page
    assert uuid_pattern(raw) == pattern
    assert masked(raw) == masked(page)  # nothing but the UUIDs changed


def test_shared_elements_stay_shared_and_distinct_ones_distinct():
    meshcat, mg = _meshcat()

    def scene() -> list[dict]:
        recorder = _SceneRecorder()
        vis = meshcat.Visualizer(window=recorder)
        ball, steel = mg.Sphere(0.1), mg.MeshPhongMaterial(color=0x808080)
        vis["a"].set_object(ball, steel)
        vis["b"].set_object(ball, steel)  # the same geometry and material
        vis["c"].set_object(mg.Mesh(mg.Sphere(0.1)))  # meshcat's default material, made once at import
        vis["d"].set_object(mg.Mesh(mg.Box([0.1, 0.2, 0.3])))  # the same default material
        vis["d"].set_object(mg.Mesh(mg.Box([0.1, 0.2, 0.3])))  # the node set again, with new elements
        return commands(recorder.get_scene())

    objects = {c["path"]: c["object"] for c in scene()}
    a, b, c, d = (objects[f"/meshcat/{n}"] for n in "abcd")
    assert a["object"]["geometry"] == b["object"]["geometry"] == a["geometries"][0]["uuid"]
    assert a["object"]["material"] == b["object"]["material"] == b["materials"][0]["uuid"]
    assert a["object"]["uuid"] != b["object"]["uuid"]
    assert c["object"]["material"] == d["object"]["material"] != a["object"]["material"]
    assert len({o["object"]["geometry"] for o in (a, c, d)}) == 3
    assert all(UUID.match(o["object"][k]) for o in (a, b, c, d) for k in ("uuid", "geometry", "material"))
    assert scene() == scene()  # also the default material, whose meshcat UUID is fixed per process only
