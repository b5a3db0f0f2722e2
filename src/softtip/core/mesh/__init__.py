"""Triangle-mesh fingertips: a CAD mesh of the skin surface as a :class:`~softtip.core.fingertip.Fingertip`.

The skin is the closed triangle mesh; its outward normal ``n(r)`` is the barycentric
interpolation of per-corner normals (angle-weighted averages of the faces around each vertex,
split at crease edges sharper than ``crease_angle_deg``), so ``n`` is continuous across
smooth edges. The soft-finger solution ``m = r × f + σ n(r)`` is found in two
steps:

1. **Cast.** The wrench's central axis (the points ``p`` with ``m = p × f + μ f``) is cast
   against the triangles, all hits, with Plücker-coordinate side tests (watertight: a line
   through a shared edge is never lost between two triangles). The triangles are grouped in
   spatially compact clusters with bounding spheres, the pre-filter. The first hit where the
   axis *enters* the skin going along ``+f`` (``f · n < 0``, the pushing side) is kept.
2. **Refine.** Newton's method on ``F(b₁, b₂, σ) = r(b) × f + σ n(b) − m`` in the
   barycentric coordinates of the current triangle, walking into the neighbouring triangle
   when a step leaves it. It is written once for numpy arrays (batch) and Python floats
   (stream), like the closed-form kernels (:mod:`softtip.core._xp`).

Meshes are loaded with `trimesh <https://trimesh.org>`_ (STL, OBJ, PLY), imported only when a
mesh fingertip is loaded.
"""


from softtip.core.mesh.capsule import capsule_mesh
from softtip.core.mesh.files import MESH_SUFFIXES, MESH_UNITS, load_mesh, rotation_from_rpy
from softtip.core.mesh.fingertip import MeshFingertip, load_mesh_fingertip, mesh_fingertip_from_table

__all__ = [
    "MeshFingertip",
    "MESH_SUFFIXES",
    "MESH_UNITS",
    "capsule_mesh",
    "load_mesh",
    "load_mesh_fingertip",
    "mesh_fingertip_from_table",
    "rotation_from_rpy",
]
