"""File formats: pattern files (JSON, OBJ, FOLD, PyKirigami) and the 2D drawings of cut files (DXF, SVG), read and written."""
