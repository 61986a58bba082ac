"""Inverse design of tubes: periodicity families, the two-stage solver, 3D files."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg
import trimesh
from fabkiri.api.tube import tube_3d_files
from fabkiri.design.quad import constraints as C
from fabkiri.design.quad.constraints import Stencils
from fabkiri.design.tube import periodic as P
from fabkiri.design.tube import solve as TS
from fabkiri.errors import InputError
from fabkiri.fabricate.tube.rolled import plate_meshes, state_frame
from fabkiri.mechanics.contract import contract
from fabkiri.pattern import geometry
from fabkiri.pattern.geometry import signed_angle
from fabkiri.pattern.kinds.periodic.sheet import lattice_seam
from fabkiri.pattern.kinds.quad.lattice import standard_pattern

from tests.designs import reconfigurable_design


def _fd(fam, x, h=1e-6):
    flat = x.ravel()
    out = np.zeros((len(fam(x)[0]), flat.size))
    for i in range(flat.size):
        e = np.zeros_like(flat)
        e[i] = h
        out[:, i] = (fam((flat + e).reshape(-1, 2))[0] - fam((flat - e).reshape(-1, 2))[0]) / (
            2 * h
        )
    return out


@pytest.mark.parametrize("spec", ["cylinder:100,60", "cone:20,15,60"])
def test_periodic_jacobians_match_finite_differences(spec):
    std = standard_pattern(4, 7, tile_size=1.0)
    st = Stencils.from_pattern(std)
    seam = lattice_seam(4, 6)
    n = len(std.nodes)
    x = std.nodes + 0.05 * np.random.default_rng(0).normal(size=std.nodes.shape)
    geo = P.unit_geometry(P.parse_tube_target(spec), 6 * np.sqrt(2.0))
    for fam in [
        P.deployed_seam(seam, st, geo, n),
        P.closed_seam(seam, st, 1, n),
        P.closed_seam(seam, st, 2, n),
        P.tube_fit(st, geo, n),
    ]:
        r, J = fam(x)
        assert J.shape == (len(r), 2 * n)
        assert np.abs(J.toarray() - _fd(fam, x)).max() < 1e-7, fam.name


def test_closed_seam_residual_is_the_closed_rotation_of_the_copy():
    """On a design that closes (not periodic), the family's value is the angle between the same edge of
    the first tile and of its would-be copy in the closed state computed by ``contract``."""
    pat = reconfigurable_design(4, 5, seed=1, amplitude=0.1)
    st = Stencils.from_pattern(pat)
    seam = lattice_seam(4, 4)
    for s in (1, 2):
        Y = contract(pat, s).corners
        t0, tc = seam.first[0], seam.copy[0]
        want = signed_angle(Y[t0, 1] - Y[t0, 0], Y[tc, 1] - Y[tc, 0])
        got = P.closed_seam(seam, st, s, len(pat.nodes))(pat.nodes)[0][0]
        assert abs(want) > 1e-4  # a real rotation, not a trivially zero one
        assert got == pytest.approx(want, abs=1e-12)


@pytest.mark.parametrize(
    "spec, message",
    [
        ("sphere:1,2", "--tube expects"),
        ("cylinder:100", "needs 2 positive"),
        ("cone:10,20,30", "must exceed"),
        ("cylinder:-1,5", "needs 2 positive"),
        ("cylinder:a,b", "must be numbers"),
    ],
)
def test_bad_tube_targets_are_one_line_input_errors(spec, message):
    with pytest.raises(InputError, match=message):
        P.parse_tube_target(spec)


def test_cli_design_tube_bad_input(tmp_path, run_cli):
    out = tmp_path / "t.json"
    code, _, err = run_cli("design", "--tube", "cylinder:100", "--tiles", "6x8", "-o", out)
    assert (
        code == 2
        and "needs 2 positive" in err
        and len(err.strip().splitlines()) == 1
        and not out.exists()
    )
    code, _, err = run_cli("design", "--tube", "cylinder:100,60", "--tiles", "6x7", "-o", out)
    assert code == 2 and "even number of columns" in err and not out.exists()


def test_the_standard_tube_is_its_own_design():
    """The standard sheet's own circumference and length: the solver keeps it (residual <= 1e-10)."""
    res = TS.design_tube(
        TS.TubeRequest(6, 8, P.parse_tube_target(f"cylinder:{80 * np.sqrt(2)},{60 * np.sqrt(2)}"))
    )
    assert res.converged and res.report["equality_max"] <= 1e-10
    assert res.report["fit_max_mm"] <= 1e-6
    assert res.pattern.tile_size == pytest.approx(10.0, rel=1e-9)


def _tube_null_rotation(closed_states: tuple[int, ...]) -> float:
    """Largest change of the deployed seam's rotation allowed, to first order, at the standard tube by
    reconfigurability plus a translation seam in ``closed_states`` (unit null vectors)."""
    prob = TS._TubeProblem(
        TS.TubeRequest(4, 6, P.parse_tube_target(f"cylinder:{60 * np.sqrt(2)},{40 * np.sqrt(2)}"))
    )
    x = TS._project(prob, prob.X0, 1e-12)[0]
    names = [
        "edge_pairs_1",
        "edge_pairs_2",
        "rings_1",
        "rings_2",
        *[f"seam_closed_{s}" for s in closed_states],
    ]
    rows = np.vstack([f(x)[1].toarray() for f in prob.eq if f.name in names])
    pairs = prob.seam.node_pairs(prob.st.tiles)
    n2 = x.size
    # deployed seam as a free rigid map: d(copy) - d(first) - dβ rot90(first) - dτ = 0
    S = np.zeros((2 * len(pairs), n2 + 3))
    i = np.arange(len(pairs))
    S[2 * i, 2 * pairs[:, 1]] = S[2 * i + 1, 2 * pairs[:, 1] + 1] = 1.0
    S[2 * i, 2 * pairs[:, 0]] = S[2 * i + 1, 2 * pairs[:, 0] + 1] = -1.0
    S[2 * i, n2], S[2 * i + 1, n2] = x[pairs[:, 0], 1], -x[pairs[:, 0], 0]
    S[2 * i, n2 + 1] = S[2 * i + 1, n2 + 2] = -1.0
    A = np.vstack([np.hstack([rows, np.zeros((len(rows), 3))]), S])
    return float(np.abs(scipy.linalg.null_space(A, rcond=1e-10)[n2]).max())


@pytest.mark.slow
def test_a_cone_is_locked_when_both_closed_states_are_cylinders():
    """Finding (docs/tubes.md): with one closed state a cylinder the deployed seam may turn (a cone);
    with both, its rotation is fixed to first order, so a cone-to-two-cylinders tube has no smooth way
    out of the standard one."""
    assert _tube_null_rotation((1,)) > 1e-3
    assert _tube_null_rotation((1, 2)) < 1e-12


@pytest.mark.slow
@pytest.mark.parametrize(
    "spec, state, axial, radial",
    [
        pytest.param(  # large axial change; its design shared with tests/mechanics/test_tube_path.py
            "cylinder:113.137,135",
            "2",
            (2.5, 3.5),
            (0.5, 0.8),
            marks=pytest.mark.xdist_group("tube-113-135"),
        ),
        (
            "cylinder:113.137,60",
            "1",
            (0.6, 0.9),
            (2.2, 3.0),
        ),  # large radial change, axial contraction
    ],
)
def test_designed_tubes_converge_verify_and_roll(
    spec, state, axial, radial, tmp_path, shared_tube_designs
):
    out = shared_tube_designs((6, 8), spec)
    assert out.valid, out.problems
    r = out.result.report
    assert r["equality_max"] <= 1e-10
    assert out.verification.ok
    ch = out.tube["changes_from_closed"][state]
    assert axial[0] < ch["axial"] < axial[1] and radial[0] < ch["radial_min"] < radial[1]
    for s in ("1", "2"):
        assert out.tube["states"][s]["seam_translation_dev_rel"] <= 1e-9
    files = tube_3d_files(out.pattern, stem="t", gif=False)
    assert set(files) == {
        f"t_{s}.{e}" for s in ("deployed", "closed1", "closed2") for e in ("obj", "stl")
    } | {"t_states.png"}
    from fabkiri.fabricate.tube.rolled import plate_overlap

    for s in (1, 2):  # both closed states non-overlapping in 3D, plate against plate
        assert plate_overlap(plate_meshes(*state_frame(out.pattern, s), 1.0))[0] < 1e-9
    tiles, frame = state_frame(out.pattern, 1)
    plates = plate_meshes(tiles, frame, 1.0)
    assert len(plates) == 48 and all(p.is_watertight and p.volume > 0 for p in plates)
    # a plate holds its tile's area times the thickness, up to the bend (|error| < thickness / radius)
    area = np.abs(geometry.signed_areas(tiles))
    vol = np.array([p.volume for p in plates])
    assert np.abs(vol / area - 1.0).max() < 1.0 / out.tube["states"]["1"]["radius_min_mm"]
    stl = trimesh.load(trimesh.util.wrap_as_stream(files["t_closed1.stl"]), file_type="stl")
    assert len(stl.faces) == sum(len(p.faces) for p in plates)
    # closed state 1 rolled: every vertex of the inner faces on the cylinder of the reported radius
    rad = out.tube["states"]["1"]["radius_min_mm"]
    obj = trimesh.load(
        trimesh.util.wrap_as_stream(files["t_closed1.obj"]), file_type="obj", process=False
    )
    assert np.abs(np.hypot(obj.vertices[:, 0], obj.vertices[:, 1]) - rad).max() < 1e-9 * rad


def test_k_copies_make_a_tube_k_periods_round():
    from fabkiri.fabricate.tube.rolled import surface_mesh
    from fabkiri.mechanics.contract import with_contracted_states
    from fabkiri.pattern.kinds.periodic.sheet import standard_tube

    tube = with_contracted_states(standard_tube(6, 8))
    one, f1 = state_frame(tube, 1)
    four, f4 = state_frame(tube, 1, copies=4)
    assert len(four) == 4 * len(one) and f4.period == pytest.approx(4 * 80.0, rel=1e-12)
    v = surface_mesh(four, f4).vertices
    assert np.abs(np.hypot(v[:, 0], v[:, 1]) - 320.0 / (2 * np.pi)).max() < 1e-9
    with pytest.raises(InputError, match="whole number"):
        state_frame(tube, 1, copies=0)


@pytest.mark.slow
def test_standard_tube_3d_files_with_deployment_gif():
    from fabkiri.mechanics.contract import with_contracted_states
    from fabkiri.pattern.kinds.periodic.sheet import standard_tube
    from PIL import Image

    files = tube_3d_files(with_contracted_states(standard_tube(6, 8)), stem="s")
    gif = Image.open(trimesh.util.wrap_as_stream(files["s_deploy.gif"]))
    assert gif.n_frames == 24
    png = Image.open(trimesh.util.wrap_as_stream(files["s_states.png"]))
    assert png.size[0] > 2 * png.size[1]  # three states side by side


def test_tubes_reached_from_perturbed_starts_are_rigid_deployable():
    """Finding behind the cone lock (docs/tubes.md): projecting perturbed sheets onto reconfigurability
    plus translation seams in both closed states lands on rigid-deployable tubes (hinge sums 0), whose
    same-colour tiles all turn by one angle, so the deployed seam turns exactly as the closed ones."""
    prob = TS._TubeProblem(
        TS.TubeRequest(4, 6, P.parse_tube_target(f"cylinder:{60 * np.sqrt(2)},{40 * np.sqrt(2)}"))
    )
    hinge_sums = C.hinge_sums(prob.st, prob.st.n_nodes)
    for seed in (1, 2):
        start = prob.X0 + 0.02 * np.random.default_rng(seed).normal(size=prob.X0.shape)
        assert np.abs(hinge_sums(start)[0]).max() > 1e-2  # the start is far from rigid
        x, eq_max, _ = TS._project(prob, start, 1e-12, 60)
        assert eq_max <= 1e-12
        assert np.abs(hinge_sums(x)[0]).max() < 1e-10


def test_plate_overlap_finds_tiles_rolled_onto_too_small_a_tube():
    from dataclasses import replace

    from fabkiri.fabricate.tube.rolled import plate_overlap
    from fabkiri.mechanics.contract import with_contracted_states
    from fabkiri.pattern.kinds.periodic.sheet import standard_tube

    tube = with_contracted_states(standard_tube(4, 6))
    tiles, frame = state_frame(tube, 1)
    worst, _ = plate_overlap(plate_meshes(tiles, frame, 0.5))
    assert worst < 1e-9  # touching neighbours only
    worst, pair = plate_overlap(plate_meshes(tiles, replace(frame, period=0.8 * frame.period), 0.5))
    assert worst > 0.05 and pair is not None  # the sheet wraps past its seam
