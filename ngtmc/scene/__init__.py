"""What a user describes: a mesh with named regions, their materials, the supports and loads
(conditions), the checks run on them (checks, scale), region matching (regions), extrusion to 3D,
gmsh import and distribution over MPI ranks."""
