"""fabkiri: compact reconfigurable kirigami from a target shape to fabrication files.

The public API follows the data flow lattice -> design -> pattern -> mechanics
-> verify -> fabricate. Import the pieces you need::

    from fabkiri.pattern import Pattern, standard_pattern, read_pattern, write_pattern
    from fabkiri.mechanics import contract, with_contracted_states, describe
"""

__version__ = "0.1.0"
