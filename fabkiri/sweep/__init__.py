"""Design sweeps: the product of a sweep file's axes, each job a :func:`fabkiri.api.design_pattern` call
(and cut, print, deploy), run on dask.distributed. ``sweep(load_spec("s.toml"), output="DIR")``.

Sits above :mod:`fabkiri.api` and below the CLI.
"""

from .run import SweepResult, sweep
from .spec import Job, SweepSpec, load_spec, spec_from_dict

__all__ = ["Job", "SweepResult", "SweepSpec", "load_spec", "spec_from_dict", "sweep"]
