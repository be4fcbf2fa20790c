"""Walls as geometry: infinite planes, finite faces (segments, triangles), their grid, meshes from files."""
