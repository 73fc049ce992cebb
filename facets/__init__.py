"""singmesh.facets: link cycles per box, their triangulation, mesh assembly."""
