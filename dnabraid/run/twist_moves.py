"""Twist-aware Metropolis moves of a torsionally constrained tether (the plectoneme), with
compiled local energies (hybrid Brownian dynamics / Monte Carlo).

The plectoneme's DNA carries a material frame per bond (one side particle per bond,
:mod:`dnabraid.forces.twist_frames`), twist joints between consecutive frames, clamps at
the surface and at the bead, and the bead's orientation particle m in a stiff rotational
trap. Brownian dynamics relaxes its slow modes (extension ~ zeta L^2 / F, and the
exchange of twist and writhe) far too slowly for micrometre molecules; these moves sample
the same Boltzmann distribution (Metropolis et al. 1953; crankshaft and pivot moves of DNA
Monte Carlo: Vologodskii et al., J. Mol. Biol. 227, 1224 (1992), Klenin & Langowski,
Biopolymers 54, 307 (2000)), interleaved with the Brownian steps.

Moves (each proposal symmetric with Jacobian 1, so plain Metropolis on the full energy,
min(1, exp(-dU / kT)) with every term of the System, gives detailed balance; the kinds are
drawn at random with fixed probabilities):

* ``crankshaft``: DNA beads i..j (1 ... ``crank_max_beads``, between the surface bead and
  the attachment) and the side particles of bonds i-1..j turned by an angle uniform in
  [-A, A] (A below) about the line through beads i-1 and j+1. The frames inside the arc
  keep their relative twist; the writhe the move makes shows up as twist at the two pivot
  joints, which the twist energy prices.
* ``pivot``: the top, beads k+1..N (attachment included) and the side particles of bonds
  k..N-1, turned about bead k (k = 0 ... N-1) by an angle uniform in
  [-``pivot_angle_rad``, ``pivot_angle_rad``] about an axis uniform on the sphere; the
  bead's orientation particle m is translated with the attachment (the bead keeps its
  angle, so the stiff trap is not disturbed; the change of the last bond's frame is priced
  by the bead clamp).
* ``frame``: a run of consecutive frames k..j (1 ... ``frame_max`` slots; slot q < N is
  side particle q, turned about its own bond through bead q; slot N is m, turned about the
  vertical through the attachment, which the trap prices) turned by the same angle psi
  uniform in [-``frame_angle_rad``, ``frame_angle_rad``]. Rotating both frames of a joint
  about their own tangents by psi leaves its angle unchanged (parallel transport commutes
  with it), so only the joints at the run's two ends change, by -psi and +psi: the move
  carries twist along the chain.
* ``particle``: one mobile particle (bead, side particle or m) displaced uniformly in the
  ball of radius ``ball_nm``: samples bond lengths, frame springs and the trap's tilt, so
  the moves alone are ergodic (tests/test_twist_moves.py).

Linking number. A move must not change Lk = Tw + Wr except through the energy: a rigid
move could carry a bond through another without ever paying the excluded volume's
barrier. Two rules keep it out, both functions of quantities the rotation leaves unchanged
(so the reverse move is refused or allowed alike and the proposal stays symmetric):

* crankshafts turn by at most A = min(``crank_angle_rad``, ``sweep_nm`` / rho), rho the
  largest distance of an arc bead from the axis: every moved point travels at most
  ``sweep_nm``. For a moved bond to pass through another their distance must fall from
  D0 to 0 and rise to D1 on the way, so D0 + D1 <= ``sweep_nm``: the state before or after
  has two bonds within sweep_nm / 2 = 1.5 nm (default), which puts beads within
  ~sqrt(1.5^2 + b^2 / 2) = 3.8 nm (b = 5 nm), each such pair costing >= 58 WCA epsilon
  (d = 4.9 nm, eps = kT): Boltzmann weight < e^-50, never accepted.
* pivots (amplitude ``pivot_angle_rad``, optionally min(., ``reach_nm`` / rho)) whose
  farthest bead travels more than ``sweep_nm`` are checked exactly for passage
  (:func:`dnabraid.kernels.twist.passage_free`: a crossing needs a moved and an unmoved
  bead within one bond length of each other at some angle on the way, found in cylinder
  coordinates about the axis) and refused if one is possible.

Bonds that share a bead cannot cross; a crossing of bonds two apart needs a bend of
~120 degrees (15 kT) at an unmoved hinge and is not checked. The frame and particle moves
move no bond by more than ``ball_nm``. The observable ``TwistWrithe`` checks Lk = bead
angle in every frame, and tests/test_twist_moves.py checks it over long move-only runs of
a wound chain.

Energies: :class:`dnabraid.kernels.LocalEnergy` (numba twins of every term, twist and
frames included: :mod:`dnabraid.kernels.twist`); the loop is
:func:`dnabraid.kernels.twist.run_twist_moves`. The guard (every ``guard_every`` calls)
and the random streams are :class:`~dnabraid.run.chain_moves.ChainMoves`'.
"""

from __future__ import annotations

import math

import numpy as np

from ..kernels.chain import NTERMS, LocalEnergy
from ..kernels.twist_loop import run_twist_moves
from .chain_moves import GUARD_ABS_PN_NM, GUARD_REL, ChainMoves, kind_weights
from .moves import MoveStats

__all__ = ["PlectonemeMoves", "TWIST_KINDS", "SWEEP_NM"]

#: Move kinds, in the order of the compiled loop's statistics rows.
TWIST_KINDS = ("crankshaft", "pivot", "frame", "particle")
#: Distance a moved bead may travel in a rigid move without the passage check (nm;
#: module docstring).
SWEEP_NM = 3.0
#: Most distance a moved bead travels in a pivot (nm): the amplitude is
#: min(angle, reach / rho). Unbounded by default: measured on the 1-um plectoneme at 0.5 pN
#: (moves alone, 45 CPU s each), the extension's ESS per CPU second was 3.2 at 30 nm
#: (kinds 2:4:2:1), 8.4 at 100 nm and 15 unbounded (kinds 1:6:1:1, pivot angle 0.3 rad;
#: 8.7 at 0.6 rad, 11.5 at 1.0 rad).
REACH_NM = math.inf
#: The longest bond the passage check allows for, in units of the rest bond length (a
#: 20 % stretch costs 0.5 k (0.2 b)^2 = 27 kT at the default bonds).
BOND_MAX_FACTOR = 1.2


def bonded_span(P, chain, sides, orientation):
    """What a pivot's energy change must search, for the compiled loop: the largest
    spread, in chain order (bead q at 2q, the side particle of bond q at 2q + 1, the
    orientation particle at 2N), of the members of any bond, hinge or twist joint of the
    energy ``P`` (-1 if some member is none of these: every moved particle's terms are
    then searched), each particle's chain order (int array, -1 elsewhere) and the members
    of the clamps (joints to the lab frame, changed by a rotation of all their members)."""
    at = {int(p): 2 * q for q, p in enumerate(chain)}
    at.update({int(p): 2 * q + 1 for q, p in enumerate(sides)})
    if orientation is not None and orientation >= 0:
        at[int(orientation)] = 2 * (len(chain) - 1)
    cpos = np.full(P.n, -1, np.int64)
    for p, c in at.items():
        cpos[p] = c
    terms = [(P.b_i[b], P.b_j[b]) for b in range(len(P.b_i))]
    terms += [(P.a_i[h], P.a_j[h], P.a_k[h]) for h in range(len(P.a_i))]
    joints = [tuple(int(x) for x in P.j_p[j, :P.j_np[j]]) for j in range(len(P.j_type))]
    lab = sorted({p for j, mem in enumerate(joints) if P.j_type[j] != 0 for p in mem})
    span = 0
    for members in terms + joints:
        if any(int(p) not in at for p in members):
            span = -1
            break
        c = [at[int(p)] for p in members]
        span = max(span, max(c) - min(c))
    return span, cpos, np.array(lab, np.int64)


class PlectonemeMoves(ChainMoves):
    """Twist-aware Metropolis moves of a torsionally constrained tether (module
    docstring); the interface of :class:`~dnabraid.run.chain_moves.ChainMoves`
    (``restart``, ``attempt``, ``summary``, ``run``).

    Parameters
    ----------
    energy : LocalEnergy, Model or openmm.System
        As :class:`ChainMoves`' (a System is turned into its LocalEnergy at first use).
    chain : int array (N + 1,)
        DNA beads, surface bead first, attachment last.
    sides : int array (N,)
        Side particle of each bond.
    orientation : int or None
        The bead's orientation particle m.
    fixed : iterable of int
        Immobile particles: the surface bead only (the moves rotate everything else).
    kT_pN_nm : float
    moves_per_call : int
    crank_angle_rad, pivot_angle_rad, frame_angle_rad : float
        Largest angles (rad, <= pi); 0 leaves the kind out.
    ball_nm : float
        Radius of the particle move's ball (nm); 0 leaves particle moves out.
    crank_max_beads, frame_max : int
        Longest crankshaft arc (beads) and frame run (slots).
    sweep_nm : float
        Bound of the distance a moved bead travels in a crankshaft or pivot (nm).
    weights : 4 floats
        Relative probabilities of crankshaft, pivot, frame and particle proposals.
    twist_spread : bool
        Crankshafts and pivots also spin every frame about its bond so that the twist
        their rotation puts on the two pivot joints is shared by all joints in inverse
        proportion to their stiffness (:func:`dnabraid.kernels.twist_loop.spread_spins`;
        symmetric, Jacobian 1); False: the pivot joints take it (the moves before
        2026-12-04).
    seed, guard_every, guard_rel, guard_abs_pN_nm
        As :class:`ChainMoves`'.
    """

    def __init__(self, energy, chain, sides, orientation, fixed, kT_pN_nm: float, *,
                 moves_per_call: int, crank_angle_rad: float = 1.0,
                 pivot_angle_rad: float = 0.3, frame_angle_rad: float = 0.3,
                 ball_nm: float = 0.3, crank_max_beads: int = 12, frame_max: int = 40,
                 sweep_nm: float = SWEEP_NM, crank_reach_nm: float = SWEEP_NM,
                 reach_nm: float = REACH_NM,
                 bond_max_nm: float | None = None, weights=(1.0, 6.0, 1.0, 1.0),
                 twist_spread: bool = False, seed: int = 1,
                 guard_every: int = 100, guard_rel: float = GUARD_REL,
                 guard_abs_pN_nm: float = GUARD_ABS_PN_NM):
        if moves_per_call < 1:
            raise ValueError("moves_per_call must be >= 1")
        amps = (float(crank_angle_rad), float(pivot_angle_rad), float(frame_angle_rad),
                float(ball_nm))
        if min(amps) < 0 or not any(a > 0 for a in amps):
            raise ValueError("move amplitudes must be >= 0, not all 0")
        if max(amps[:3]) > math.pi:
            raise ValueError("crank_angle_rad, pivot_angle_rad and frame_angle_rad must be "
                             "<= pi")
        if crank_max_beads < 1 or frame_max < 1:
            raise ValueError("crank_max_beads and frame_max must be >= 1")
        if not sweep_nm > 0 or not reach_nm > 0:
            raise ValueError("sweep_nm and reach_nm must be > 0")
        chain = np.asarray(chain, np.int64)
        sides = np.asarray(sides, np.int64)
        if len(chain) < 3 or len(sides) != len(chain) - 1:
            raise ValueError("PlectonemeMoves needs a chain of >= 3 beads and one side "
                             "particle per bond")
        fixed = {int(i) for i in fixed}
        if not fixed <= {int(chain[0])}:
            raise ValueError("PlectonemeMoves: only the surface bead may be immobile")
        w = kind_weights(weights, amps, guard_every)
        self._energy = energy
        self.kT = float(kT_pN_nm)
        self.moves_per_call = int(moves_per_call)
        self.crank_angle, self.pivot_angle, self.frame_angle, self.ball_nm = amps
        self.bead_nm = self.ball_nm  # ChainMoves.energy refuses ball moves with constraints
        self.crank_max = int(crank_max_beads)
        self.frame_max = int(frame_max)
        self.sweep_nm = float(sweep_nm)
        self.reach_nm = float(reach_nm)
        self.crank_reach_nm = float(crank_reach_nm)
        self.bond_max_nm = None if bond_max_nm is None else float(bond_max_nm)
        self.twist_spread = bool(twist_spread)
        self.weights = w / w.sum()
        self._cum = np.cumsum(self.weights)
        self._cum[-1] = 1.0 + 1e-12
        self.seed = int(seed)
        self.guard_every = int(guard_every)
        self.guard_rel = float(guard_rel)
        self.guard_abs = float(guard_abs_pN_nm)
        self._chain = chain
        self._sides = sides
        self._m = -1 if orientation is None else int(orientation)
        self._fixed = fixed
        self._bnd = None
        self._span = -1
        self._mobile = None
        self.kinds = [k for k, x in zip(TWIST_KINDS, self.weights) if x > 0]
        self.stats = {k: MoveStats() for k in self.kinds}
        self._stats = np.zeros((4, 3), np.int64)
        self.rng = np.random.default_rng([self.seed, 0])
        self._calls = 0
        self.guard_checks = 0
        self.guard_max_diff = 0.0

    @classmethod
    def for_model(cls, model, **kw) -> PlectonemeMoves:
        """Moves of a built plectoneme model (its chain, sides, orientation particle,
        fixed bead and kT), with the model's LocalEnergy."""
        return cls(LocalEnergy(model), model.chains[0], model.sides, model.bead_orientation,
                   model.fixed, model.dna.kT, **kw)

    def _tables(self) -> None:
        """The joint at each frame boundary and the mobile particles, from the energy."""
        P = self.energy.params
        c, s, m = self._chain, self._sides, self._m
        nb = len(s)
        bnd = np.full(nb + 1, -1, np.int64)
        key = {}
        for j in range(len(P.j_type)):
            key[(int(P.j_type[j]),) + tuple(int(x) for x in P.j_p[j, :P.j_np[j]])] = j
        bnd[0] = key.get((1, int(c[0]), int(c[1]), int(s[0])), -1)
        for q in range(1, nb):
            bnd[q] = key.get((0, int(c[q - 1]), int(c[q]), int(c[q + 1]), int(s[q - 1]),
                              int(s[q])), -1)
        if m >= 0:
            bnd[nb] = key.get((2, int(c[-2]), int(c[-1]), int(s[-1]), m), -1)
        if np.any(bnd[1:nb] < 0):
            raise ValueError("PlectonemeMoves: the System lacks interior twist joints of the "
                             "chain's frames")
        self._bnd = bnd
        self._span, self._cpos, self._lab = bonded_span(P, c, s, m)
        parts = list(c) + list(s) + ([m] if m >= 0 else [])
        self._mobile = np.array([p for p in parts if int(p) not in self._fixed], np.int64)
        if self.bond_max_nm is None:
            r0 = [P.b_r0[b] for b in range(len(P.b_i)) if P.b_t[b] == 0]
            if not r0:
                raise ValueError("PlectonemeMoves: no stretch bonds; pass bond_max_nm")
            self.bond_max_nm = BOND_MAX_FACTOR * float(max(r0))

    def _run(self, pos: np.ndarray, n: int) -> tuple[np.ndarray, float]:
        if self._bnd is None:
            self._tables()
        uni = self.rng.random((n, 6))
        gau = self.rng.standard_normal((n, 3))
        before = self._stats.copy()
        terms = np.zeros(NTERMS)
        absum = run_twist_moves(pos, self.energy.params, self._chain, self._sides, self._m,
                                self._bnd, self._mobile, self._cum, self.crank_max,
                                self.crank_angle, self.pivot_angle, self.sweep_nm,
                                self.crank_reach_nm, self.reach_nm, self.bond_max_nm,
                                self.frame_angle, self.frame_max, self.ball_nm, self.kT,
                                uni, gau, self._stats, terms, self._span, self._cpos,
                                self._lab, self.twist_spread)
        self._tally(before, TWIST_KINDS)
        return terms, float(absum)

    def summary(self) -> dict:
        """Amplitudes, the guard's record and the counts of each kind."""
        return {"crank_angle_rad": self.crank_angle, "pivot_angle_rad": self.pivot_angle,
                "frame_angle_rad": self.frame_angle, "ball_nm": self.ball_nm,
                "crank_max_beads": self.crank_max, "frame_max": self.frame_max,
                "sweep_nm": self.sweep_nm,
                "reach_nm": self.reach_nm if math.isfinite(self.reach_nm) else None,
                "crank_reach_nm": self.crank_reach_nm,
                "bond_max_nm": self.bond_max_nm, "moves_per_call": self.moves_per_call,
                "twist_spread": self.twist_spread,
                "guard_checks": self.guard_checks,
                "guard_max_diff_pN_nm": self.guard_max_diff,
                **{k: v.to_dict() for k, v in self.stats.items()}}
