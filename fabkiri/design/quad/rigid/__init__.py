"""The rigid-deployable quad family in reduced coordinates and its solver."""
