"""What a user describes: a mesh with named regions, their materials, the supports and loads
(conditions), the checks run on them (checks, scale), region matching (regions), extrusion to 3D,
gmsh import and distribution over MPI ranks."""
from ngtmc.scene.conditions import DisplacementField, DisplacementLoad, Point, Support, Traction
from ngtmc.scene.distributed import Ranks, check_supported, distribute, refuse_unsupported
from ngtmc.scene.extrusion import extrude
from ngtmc.scene.gmsh import read_gmsh
from ngtmc.scene.regions import (
    centroids, coordinates, element_vertices, matches, neighbours, regex, region_names, vertices_of,
    within,
)
from ngtmc.scene.scale import check_load_scale
from ngtmc.scene.scene import Regulariser, Scene
from ngtmc.scene.warnings import ElementWarning, ResolutionWarning, ScaleWarning

__all__ = [
    'DisplacementField', 'DisplacementLoad', 'ElementWarning', 'Point', 'Ranks', 'Regulariser',
    'ResolutionWarning', 'ScaleWarning', 'Scene', 'Support', 'Traction', 'centroids',
    'check_load_scale', 'check_supported', 'coordinates', 'distribute', 'element_vertices',
    'extrude', 'matches', 'neighbours', 'read_gmsh', 'refuse_unsupported', 'regex', 'region_names',
    'vertices_of', 'within',
]
