"""Inverse design of quad (rotating-squares) kirigami: the full solver and its routes."""
