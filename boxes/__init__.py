"""singmesh.boxes: Bernstein forms on boxes, the octree, edge roots, face links."""
