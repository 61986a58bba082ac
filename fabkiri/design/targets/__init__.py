"""Target outlines: built-in shapes, files, the target curve and projection onto it."""
