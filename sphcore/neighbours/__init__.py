"""Neighbour search: cell keys and their sort, the cell grid, kept pair lists."""
