"""The checks of an MJCF file around MuJoCo's compiler: every mesh (of the file and its includes) within the
mesh limits before MuJoCo reads it, and every number MuJoCo computed finite and in range after."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from runner.language.mesh_limits import check_mesh_file
from runner.language.model_numbers import check_mjcf_numbers, check_number, check_vertices
from runner.language.robot_desc import ModelFileError, resolved
from runner.language.urdf_xml import parse_xml

#: included files followed when looking for meshes (MuJoCo refuses a file that includes itself)
MAX_INCLUDES = 64


def check_meshes(tree: Any, file: Path) -> None:
    """Every `<mesh file=...>` of the file and of the files it includes (their numbers checked too) within the
    mesh limits, before MuJoCo reads them (runner.language.mesh_limits); a file that cannot be found or read
    is left to MuJoCo's own message."""
    compiler = tree.getroot().find("compiler")
    folder = file.parent
    if compiler is not None:
        folder = folder / (compiler.get("meshdir") or compiler.get("assetdir") or "")
    todo, seen = [(tree, file)], {file.resolve()}
    while todo:
        current, owner = todo.pop()
        for element in current.getroot().iter("mesh", "include"):
            name, line = element.get("file"), element.sourceline or 0
            if not name:
                continue
            base = folder if element.tag == "mesh" else file.parent  # includes are relative to the main file
            path = resolved(base / name, owner, line, name)
            if element.tag == "mesh" and path.is_file():
                check_mesh_file(path, owner, line, name)
            elif element.tag == "include" and path.is_file() and path not in seen and len(seen) < MAX_INCLUDES:
                seen.add(path)
                included = parse_xml(path)
                check_mjcf_numbers(included, path)
                todo.append((included, path))


def check_compiled(model: Any, file: Path, bodies: list[str], lines: dict[tuple[str, str], int]) -> None:
    """What MuJoCo computed (defaults, includes and `fromto` applied) finite and within +-MAX_MAGNITUDE, at
    the body's line: the main file's attributes were checked one by one before (check_mjcf_numbers)."""
    for b in range(1, model.nbody):
        geoms = range(int(model.body_geomadr[b]), int(model.body_geomadr[b]) + int(model.body_geomnum[b]))
        fields = {"pos": model.body_pos[b], "quat": model.body_quat[b], "mass": [model.body_mass[b]],
                  "inertia": model.body_inertia[b], "geom size": [v for g in geoms for v in model.geom_size[g]],
                  "geom pos": [v for g in geoms for v in model.geom_pos[g]]}  # fmt: skip
        for what, values in fields.items():
            for value in np.asarray(values, dtype=float).ravel():
                problem = check_number(float(value), "any")
                if problem is not None:
                    raise ModelFileError(file, lines.get(("body", bodies[b]), 0),
                                         f"body `{bodies[b]}`: its {what} {float(value)!r} {problem}")  # fmt: skip
    if model.nmeshvert:
        line = next((line for (tag, _), line in lines.items() if tag == "mesh"), 0)
        check_vertices(np.asarray(model.mesh_vert), file, line, "of the model")
