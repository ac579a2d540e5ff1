"""Scene files: the description of one simulation (TOML, SI units), its keys, checks and
the built-in scenes.

The names most scripts need are re-exported here (``from billiard.scene import
load_scene``); the modules are :mod:`~billiard.scene.scene` (loading, writing, built-in
scenes), :mod:`~billiard.scene.spec` (the sections as validated specifications),
:mod:`~billiard.scene.keys` (which keys exist), :mod:`~billiard.scene.checks` (value
checks), :mod:`~billiard.scene.toml_text` (TOML writing) and
:mod:`~billiard.scene.userfile` (reading a file a user names).
"""

from billiard.scene.scene import (
    PAPER_SCENES,
    Scene,
    SceneError,
    builtin_scenes,
    load_scene,
    scene_from_dict,
    scene_to_toml,
    with_values,
)

__all__ = [
    "PAPER_SCENES",
    "Scene",
    "SceneError",
    "builtin_scenes",
    "load_scene",
    "scene_from_dict",
    "scene_to_toml",
    "with_values",
]
