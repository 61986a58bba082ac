"""The 3D tube pictures refuse a flat sheet in one line (bad input), as the tube exports do."""

import pytest
from fabkiri.errors import InputError
from fabkiri.mechanics.deploy import deployment_path
from fabkiri.pattern.kinds.quad.lattice import standard_pattern
from fabkiri.render.tube import deployment_gif_3d


def test_deployment_gif_3d_of_a_flat_sheet_is_bad_input():
    # found by mypy: the seam of a flat sheet is None, and the GIF read it before anything checked it
    flat = standard_pattern(2, 2)
    with pytest.raises(InputError, match="no seam: it is a flat sheet"):
        deployment_gif_3d(flat, deployment_path(flat, 4))
