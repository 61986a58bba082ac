"""The quad (rotating-squares) tessellation."""
