"""Print styles, one module each; each registers itself with :func:`..printjob.register_style`."""
