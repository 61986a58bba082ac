"""Tessellation kinds: one folder per kind (its lattice and fold rules) and the registry that names them."""
