"""fabkiri: compact reconfigurable kirigami from a target shape to fabrication files.

The public API follows the data flow lattice -> design -> pattern -> mechanics
-> verify -> fabricate. Import the pieces you need::

    from fabkiri.pattern import Pattern, standard_pattern, read_pattern, write_pattern
    from fabkiri.mechanics import contract, with_contracted_states, describe

and from a target outline to cut or print files in one call::

    result = fabkiri.make("star", size=150, material="acrylic-3", output="outputs/star")
"""

__version__ = "0.1.0"

# loaded on first use (PEP 562), so `import fabkiri` stays cheap: the front door needs numpy and more
_LAZY = {"make": "fabkiri.api.maker", "MakeResult": "fabkiri.api.maker_result"}


def __getattr__(name: str):
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'fabkiri' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted([*globals(), *_LAZY])
