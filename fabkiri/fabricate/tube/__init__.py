"""Tubes: the flat sheet a tube is cut from and its states rolled into 3D."""
