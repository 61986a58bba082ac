"""Pictures: energy plots and deployment animations (matplotlib Agg + pillow), the design preview (pillow).

Renderers return bytes; the caller writes them with :mod:`fabkiri.fileio`.
"""

from .deployment import deployment_gif, energy_plot_png

__all__ = ["energy_plot_png", "deployment_gif"]
