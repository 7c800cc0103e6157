"""DART mesh shapes from ``Shape.mesh`` (convex hulls and static triangle meshes).

dartpy 6.20 has no convex-mesh shape and binds no way to make a ``MeshShape`` from arrays: its only
constructor takes an assimp ``aiScene``, which Python cannot build. So the mesh is written once as a binary
STL into a temporary folder and loaded by DART's own URDF loader (``DartLoader``, through assimp); the
loaded ``MeshShape`` is kept and the loader's skeleton dropped. Assimp stores vertices as float32, and so
does binary STL: the hull DART collides with is ``Shape.mesh`` rounded to float32 (at most 6e-8 of a
coordinate: 3e-8 m on the kuka's 0.5 m links), the same vertices and triangles, nothing re-hulled.

DART's collision detectors collide a ``MeshShape`` as a triangle mesh (ODE's ``dTriMesh`` for the default
``ode`` detector): for a closed convex hull that is exactly the hull's surface, but its interior is not
solid, so a body that passes wholly inside another (deeper than the other's smallest half-width in one
step) is not pushed out (docs/backends/dart.md, "Robots").
"""

from __future__ import annotations

import functools
import tempfile
from pathlib import Path
from typing import Any

import dartpy as dart
import numpy as np
import trimesh

from ..errors import UnsupportedFeature
from ..types import Mesh


@functools.lru_cache(maxsize=256)
def mesh_shape(mesh: Mesh) -> Any:
    """A DART ``MeshShape`` holding ``mesh``'s triangles in its shape frame (one per distinct mesh; shared
    by the bodies that use it, as DART shapes may be)."""
    if not mesh.faces:
        raise UnsupportedFeature(f"Backend `dart` cannot build the empty mesh `{mesh.source}`.")
    triangles = trimesh.Trimesh(
        vertices=np.asarray(mesh.vertices, dtype=float),
        faces=np.asarray(mesh.faces, dtype=np.int64),
        process=False,
    )
    with tempfile.TemporaryDirectory(prefix="dart-mesh-") as folder:
        path = Path(folder) / "mesh.stl"
        triangles.export(file_obj=str(path), file_type="stl")
        urdf = (
            '<robot name="mesh"><link name="mesh"><collision><geometry>'
            f'<mesh filename="{path.as_uri()}"/></geometry></collision></link></robot>'
        )
        skeleton = dart.utils.DartLoader().parseSkeletonString(urdf, dart.common.Uri(Path(folder).as_uri() + "/"))
    node = skeleton.getBodyNode(0) if skeleton is not None else None
    if node is None or node.getNumShapeNodes() != 1:
        raise UnsupportedFeature(f"Backend `dart` could not load the mesh `{mesh.source}` through assimp.")
    return node.getShapeNode(0).getShape()
