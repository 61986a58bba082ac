"""The kagome (rotating-triangles) tessellation."""
