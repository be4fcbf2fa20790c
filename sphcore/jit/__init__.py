"""numba helpers: serial or parallel builds by size, the on-disk cache kept consistent with the sources."""
