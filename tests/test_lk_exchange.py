"""The mapped swap of the trap-angle replica exchange (workflows/lk_exchange.py, docs/validation.md
2.3n): its inverse, what it moves, and the twist energy it adds against rod theory."""

from conftest import load_workflow
import numpy as np
import pytest


@pytest.fixture(scope="module")
def lx():
    return load_workflow("lk_exchange")


def test_swap_map_is_a_twist_of_the_chain_with_its_torsional_stiffness(lx):
    """T_D spreads a bead turn D over the frames as pure twist: on a 100 nm tether's exact
    start (seed 3, trap angle turned with it) the energy changes only in the twist terms, and
    its part even in D is C kT D^2 / (2 L), the rod's twist energy of Delta Lk = D / 2 pi
    (Moroz & Nelson 1997: E = 2 pi^2 C kT Delta Tw^2 / L), to round-off (measured 9e-15,
    asserted 1e-9:
    the joints take D/N each and the two clamps D/2N; the odd part is the start's own twist,
    Tw = -Wr). T_-D undoes T_D to round-off (detailed balance of
    the swap needs it), and only the frames' side particles and the bead's orientation move,
    each at its distance from its axis."""
    s, m, mv = lx.ref.moves_chain(0.0, 100.0, 1.0, 3)
    c, sides, mo = np.asarray(m.chains[0]), np.asarray(m.sides), int(m.bead_orientation)
    x = np.array(m.positions)
    e0 = mv.energy.total_terms(x)
    D = 0.5
    de = {}
    for sgn in (1.0, -1.0):
        mv.energy.set_trap_angle(sgn * D)
        y = lx.swap_map(x, c, sides, mo, sgn * D, 1.0)
        e1 = mv.energy.total_terms(y)
        changed = {k for k in e0 if abs(e1[k] - e0[k]) > 1e-9}
        assert changed <= {"twist"}, changed
        de[sgn] = e1["twist"] - e0["twist"]
        back = lx.swap_map(y, c, sides, mo, -sgn * D, 1.0)
        assert np.abs(back - x).max() < 1e-9
        moved = np.flatnonzero(np.abs(y - x).max(axis=1) > 1e-12)
        assert set(moved) <= set(sides.tolist()) | {mo}
        for q, p in enumerate(sides):  # each side particle keeps its distances to its bond
            for b in (c[q], c[q + 1]):
                assert np.linalg.norm(y[p] - y[b]) == pytest.approx(np.linalg.norm(x[p] - x[b]),
                                                                    abs=1e-9)
        assert np.linalg.norm(y[mo] - y[c[-1]]) == pytest.approx(
            np.linalg.norm(x[mo] - x[c[-1]]), abs=1e-9)
    even = 0.5 * (de[1.0] + de[-1.0])
    theory = s.twist_persistence_nm * m.dna.kT * D * D / (2 * s.length_nm)
    assert even == pytest.approx(theory, rel=1e-9)
