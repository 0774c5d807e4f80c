"""exactff-scene/1 JSON: polygons with optional names, groups and materials."""

import json

from ..scene import build_scene

__all__ = ["scene_from_json", "read_scene_json"]


def scene_from_json(data, **options):
    """Build a scene from a parsed ``exactff-scene/1`` document (its ``surfaces``);
    ``options`` go to :func:`exactff.scene.build_scene` (``nonplanar``, ``degenerate``,
    ``planarity_rtol``).

    Raises
    ------
    ValueError
        The document is not an ``exactff-scene/1`` object with a non-empty list of
        surfaces, each an object with ``vertices`` (the message says what is missing).
    SceneError
        A surface's polygon is ill-formed.
    """
    if not isinstance(data, dict):
        raise ValueError(f"expected a JSON object (exactff-scene/1), got a {type(data).__name__}")
    if data.get("schema") != "exactff-scene/1":
        raise ValueError(f"schema: expected 'exactff-scene/1', got {data.get('schema')!r}")
    surfaces = data.get("surfaces")
    if not isinstance(surfaces, list) or not surfaces:
        raise ValueError("surfaces: expected a non-empty list of surfaces")
    for i, s in enumerate(surfaces):
        if not isinstance(s, dict) or "vertices" not in s:
            raise ValueError(f"surfaces[{i}]: expected an object with 'vertices'")
    return build_scene(
        [s["vertices"] for s in surfaces],
        names=[s.get("name") for s in surfaces],
        groups=[s.get("group") for s in surfaces],
        materials=[s.get("material") for s in surfaces],
        sources=[f"surfaces[{i}]" for i in range(len(surfaces))],
        **options,
    )


def read_scene_json(path, **options):
    """Read an ``exactff-scene/1`` JSON file (see ``shared/scenes/README.md``)."""
    with open(path, encoding="utf-8") as fh:
        try:
            data = json.load(fh)
        except json.JSONDecodeError as exc:
            raise ValueError(f"{path}:{exc.lineno}: invalid JSON: {exc.msg}") from None
    try:
        return scene_from_json(data, **options)
    except ValueError as exc:
        if type(exc) is ValueError:   # the document's structure (SceneError passes as is)
            raise ValueError(f"{path}: {exc}") from None
        raise
