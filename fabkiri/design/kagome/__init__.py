"""Inverse design of kagome (rotating-triangles) kirigami."""
