"""3D printing: a closed state to printable solids, print styles, presets and their checked files."""
