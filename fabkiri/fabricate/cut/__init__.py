"""Laser cutting: a closed state to cut sheets, hinges, labels, layouts and their checked files."""
