"""Triangle geometry: meshes and their loading, built-in shapes, affine transforms, and the BVH build."""

from spectrace.geometry.bvh import BVH, BVH_NODE_DTYPE, build_bvh, sah_cost
from spectrace.geometry.mesh import TriangleMesh, load_mesh
from spectrace.geometry.primitives import cube, rectangle, sphere
from spectrace.geometry.transforms import apply_transform, transform_matrix

__all__ = [
    "BVH",
    "BVH_NODE_DTYPE",
    "TriangleMesh",
    "apply_transform",
    "build_bvh",
    "cube",
    "load_mesh",
    "rectangle",
    "sah_cost",
    "sphere",
    "transform_matrix",
]
