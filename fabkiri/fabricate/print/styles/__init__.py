"""Print styles: the built-ins' rules in :mod:`.rules` (registered with :func:`..job.register_style`),
their building one module each."""
