"""singmesh.skeleton: singular points, their classification, skeleton curves."""
