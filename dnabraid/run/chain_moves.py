"""Metropolis crankshaft, pivot and bead moves of open bead chains with compiled local
energies (hybrid Brownian dynamics / Monte Carlo for tethers).

Brownian dynamics relaxes a chain's slowest mode in a time ~ zeta L^2 / (pi^2 F): a 600-nm
tether at 0.3 pN needs far more steps than a run can afford (its default run ends NOT
CONVERGED). The field's standard for equilibrium averages of such chains is Metropolis
Monte Carlo (Metropolis et al. 1953) with crankshaft and pivot moves (Vologodskii et al.,
J. Mol. Biol. 227, 1224 (1992); Klenin & Langowski, Biopolymers 54, 307 (2000); the pivot
algorithm: Lal, Mol. Phys. 17, 57 (1969); Madras & Sokal, J. Stat. Phys. 50, 109 (1988)).
Equilibrium averages do not depend on how a state is reached, so these moves, interleaved
with the Brownian steps, leave the Boltzmann distribution unchanged; their time
correlations are not physical (for kinetics, run without them).

Moves (each proposal symmetric, so the Metropolis rule min(1, exp(-dU / kT)) alone gives
detailed balance; kinds are drawn at random with fixed probabilities, so the mixture is
reversible too):

* ``crankshaft``: an arc of beads i..j (1 ... ``crank_max_beads`` beads, none immobile,
  bounded by beads i-1 and j+1 of the same chain) turned by an angle uniform in
  [-``crank_angle_rad``, ``crank_angle_rad``] about the line through beads i-1 and j+1.
  Bond lengths are kept; the arc's position and length are drawn independently of the
  state, and the reverse move is the same arc turned back.
* ``pivot``: the end of a chain, beads i..last (i >= 1, none immobile), turned about bead
  i-1 by an angle uniform in [-``pivot_angle_rad``, ``pivot_angle_rad``] about an axis
  uniform on the sphere (R and R^-1 equally likely). It moves the attachment, so it is
  the move that changes the extension.
* ``bead``: one mobile bead displaced uniformly in the ball of radius ``bead_move_nm``.
  Crankshaft and pivot keep bond lengths; this move samples them (harmonic bonds), so the
  moves alone are ergodic and sample the exact distribution (tests/test_chain_moves.py).

dU comes from :class:`dnabraid.kernels.LocalEnergy` (numba; only the moved particles'
terms), and a whole call's proposals run in one compiled loop on a copy of the positions:
``set_pos`` is called once. A guard checks, every ``guard_every`` calls, that the
accepted moves' local energy changes add up to the kernel's total energy change (term by
term, round-off) and that this equals the engine's energy change (``energy_fn``, the whole
Context; other packed copies do not move, so the change is this replica's) within
``guard_rel`` x |E| + ``guard_abs``: a mismatch raises :class:`RuntimeError` naming the
term or the two numbers.

Random numbers come from ``numpy.random.default_rng([seed, stream])`` (stream 0 before
the first :meth:`ChainMoves.restart`, 1 + segment index after), drawn as whole arrays per
call, so a resumed or repeated run makes the same moves.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from ..kernels.braid_moves import BRAID_KINDS, run_braid_moves
from ..kernels.chain import NTERMS, TERMS, LocalEnergy, run_chain_moves
from .moves import MoveStats

__all__ = ["BraidMoves", "ChainMoves", "KINDS", "BRAID_KINDS", "GUARD_REL", "GUARD_ABS_PN_NM",
           "MIRRORED_UNIFORMS", "mirror_random"]

#: Move kinds, in the order of the compiled loop's statistics rows.
KINDS = ("crankshaft", "pivot", "bead")

#: Guard tolerance, relative to the larger |engine energy| before and after the call (all
#: packed copies: their energy and their offsets from the origin grow together). The CPU
#: platform evaluates the WCA pairs from single-precision positions (rounding ~6e-8 |x|);
#: workflows/results/benchmark_chain_moves.txt measures the mismatch over 100 calls of the
#: default moves: 7e-13 pN nm without contacts, 1.6e-4 pN nm for a contact-rich tether
#: (1500 nm, d = 31 nm, |E| = 1936 pN nm) at the origin and 9.8e-4 pN nm shifted by 3000
#: nm, as a packed copy is, against a tolerance of 2.9e-3 pN nm. Not measured on CUDA or
#: OpenCL (mixed precision: every force from single-precision positions), where it may
#: need widening (``guard_rel``, ``guard_abs_pN_nm``).
GUARD_REL = 1e-6
#: Guard tolerance, absolute part (pN nm).
GUARD_ABS_PN_NM = 1e-3


#: Per braid move kind, the columns of its uniforms that carry a sign under the y -> -y
#: mirror (u -> 1 - u): the crankshaft's angle, the shear's azimuth, the twist's angle, the
#: sway's angle and azimuth, the pivot's and the tilt's angles (the bead move's Gaussian y
#: is negated). tests/test_braid_mirror_moves.py checks that a chain fed these from the
#: mirrored start is the mirror of the original, move by move.
MIRRORED_UNIFORMS = {0: (4,), 2: (3,), 3: (2,), 4: (2, 3), 5: (2,), 6: (2,)}


def mirror_random(cum, uni: np.ndarray, gau: np.ndarray,
                  mirrored: dict = MIRRORED_UNIFORMS) -> tuple[np.ndarray, np.ndarray]:
    """The random numbers of the braid moves' y -> -y mirror (``mirrored``: per kind, the
    uniforms' columns that flip; default :data:`MIRRORED_UNIFORMS`), as new arrays;
    ``cum`` the kinds' cumulative weights (the kind of each proposal)."""
    uni = uni.copy()
    gau = gau.copy()
    kind = np.minimum(np.searchsorted(cum, uni[:, 0], side="right"), len(BRAID_KINDS) - 1)
    for k, cols in mirrored.items():
        for c in cols:
            uni[kind == k, c] = 1.0 - uni[kind == k, c]
    gau[kind == 1, 1] *= -1.0
    return uni, gau


def kind_weights(weights, amps, guard_every: int) -> np.ndarray:
    """The proposal weights of the move kinds, zero for a kind without amplitude; checks
    them and the guard interval (ValueError)."""
    w = np.array([float(x) for x in weights], float)
    if w.shape != (len(amps),) or np.any(w < 0):
        raise ValueError(f"weights must be {len(amps)} numbers >= 0")
    w = np.where(np.array(amps) > 0, w, 0.0)
    if w.sum() <= 0:
        raise ValueError("no move kind has both a weight and an amplitude")
    if guard_every < 0:
        raise ValueError("guard_every must be >= 0")
    return w


class ChainMoves:
    """Metropolis crankshaft, pivot and bead moves of open chains (module docstring); the
    interface of :class:`dnabraid.run.moves.RigidMoves` (``restart``, ``attempt``,
    ``summary``).

    Parameters
    ----------
    energy : dnabraid.kernels.LocalEnergy, dnabraid.chains.Model or openmm.System
        The model's energy (every term of its System); a Model or System is turned into
        its :class:`~dnabraid.kernels.LocalEnergy` at the first call, so that it sees
        every Force added after the moves were made (a scene makes them while it builds).
    chains : list of int arrays
        Open chains, bead indices in chain order (surface -> attachment).
    fixed : iterable of int
        Immobile particles (never moved).
    kT_pN_nm : float
    moves_per_call : int
        Proposals per call (per replica).
    crank_angle_rad, pivot_angle_rad : float
        Largest rotation angles (rad, <= pi); 0 leaves that kind out.
    bead_move_nm : float
        Radius of the bead move's ball (nm); 0 leaves bead moves out.
    crank_max_beads : int
        Most beads of a crankshaft arc.
    weights : 3 floats
        Relative probabilities of crankshaft, pivot and bead proposals (kinds left out get
        none).
    seed : int
    guard_every : int
        Calls between guard checks (the first call after every restart is checked; 0 =
        never).
    guard_rel, guard_abs_pN_nm : float
        Guard tolerance of the engine comparison.
    """

    def __init__(self, energy: LocalEnergy, chains, fixed, kT_pN_nm: float, *,
                 moves_per_call: int, crank_angle_rad: float, pivot_angle_rad: float,
                 bead_move_nm: float, crank_max_beads: int = 8, weights=(2.0, 1.0, 1.0),
                 seed: int = 1, guard_every: int = 100, guard_rel: float = GUARD_REL,
                 guard_abs_pN_nm: float = GUARD_ABS_PN_NM):
        if moves_per_call < 1:
            raise ValueError("moves_per_call must be >= 1")
        amps = (float(crank_angle_rad), float(pivot_angle_rad), float(bead_move_nm))
        if min(amps) < 0 or not any(a > 0 for a in amps):
            raise ValueError("crank_angle_rad, pivot_angle_rad and bead_move_nm must be >= 0, "
                             "not all 0")
        if amps[0] > math.pi or amps[1] > math.pi:
            raise ValueError("crank_angle_rad and pivot_angle_rad must be <= pi")
        if crank_max_beads < 1:
            raise ValueError("crank_max_beads must be >= 1")
        w = kind_weights(weights, amps, guard_every)
        self._energy = energy
        self.kT = float(kT_pN_nm)
        self.moves_per_call = int(moves_per_call)
        self.crank_angle, self.pivot_angle, self.bead_nm = amps
        self.crank_max = int(crank_max_beads)
        self.weights = w / w.sum()
        self._cum = np.cumsum(self.weights)
        self._cum[-1] = 1.0 + 1e-12  # round-off: every uniform in [0, 1) picks a kind
        self.seed = int(seed)
        self.guard_every = int(guard_every)
        self.guard_rel = float(guard_rel)
        self.guard_abs = float(guard_abs_pN_nm)
        chains = [np.asarray(c, np.int64) for c in chains]
        if not chains or any(len(c) < 2 for c in chains):
            raise ValueError("ChainMoves needs chains of >= 2 beads")
        fixed = {int(i) for i in fixed}
        self._c_ptr = np.concatenate([[0], np.cumsum([len(c) for c in chains])]).astype(
            np.int64)
        self._c_beads = np.concatenate(chains).astype(np.int64)
        isfixed = np.array([int(i) in fixed for i in self._c_beads], np.int64)
        self._c_fixed = np.concatenate([[0], np.cumsum(isfixed)]).astype(np.int64)
        self._mobile = self._c_beads[isfixed == 0].copy()
        self.kinds = [k for k, x in zip(KINDS, self.weights) if x > 0]
        self.stats = {k: MoveStats() for k in self.kinds}
        self._stats = np.zeros((3, 3), np.int64)
        self.rng = np.random.default_rng([self.seed, 0])
        self._calls = 0
        self.guard_checks = 0
        self.guard_max_diff = 0.0

    @property
    def energy(self) -> LocalEnergy:
        """The :class:`~dnabraid.kernels.LocalEnergy` of the moves (built on first use)."""
        if not isinstance(self._energy, LocalEnergy):
            self._energy = LocalEnergy(self._energy)
        if self.bead_nm > 0 and self._energy.n_constraints:
            raise ValueError("ChainMoves: bead moves would break the System's rigid bonds "
                             "(constraints); set bead_move_nm = 0")
        return self._energy

    @classmethod
    def for_model(cls, model, **kw) -> ChainMoves:
        """Moves of ``model.chains`` (immobile ``model.fixed``) at the model's kT, with the
        model's :class:`~dnabraid.kernels.LocalEnergy`; keywords as the constructor's."""
        return cls(LocalEnergy(model), model.chains, model.fixed, model.dna.kT, **kw)

    def restart(self, stream: int) -> None:
        """Random numbers from stream ``stream`` of this seed; statistics kept."""
        self.rng = np.random.default_rng([self.seed, 1 + int(stream)])
        self._calls = 0

    def run(self, pos: np.ndarray, n_moves: int | None = None) -> tuple[np.ndarray, np.ndarray]:
        """``n_moves`` proposals (default ``moves_per_call``) from ``pos`` (nm), without an
        engine; returns (new positions, accepted energy change per term of
        :data:`dnabraid.kernels.TERMS`, pN nm)."""
        pos = np.array(pos, np.float64, copy=True, order="C")
        terms, _ = self._run(pos, self.moves_per_call if n_moves is None else int(n_moves))
        return pos, terms

    def _run(self, pos: np.ndarray, n: int) -> tuple[np.ndarray, float]:
        uni = self.rng.random((n, 6))
        gau = self.rng.standard_normal((n, 3))
        before = self._stats.copy()
        terms = np.zeros(NTERMS)
        absum = run_chain_moves(pos, self.energy.params, self._c_ptr, self._c_beads,
                                self._c_fixed, self._mobile, self._cum, self.crank_max,
                                self.crank_angle, self.pivot_angle, self.bead_nm, self.kT,
                                uni, gau, self._stats, terms)
        self._tally(before, KINDS)
        return terms, float(absum)

    def _tally(self, before, kinds) -> None:
        """Add the counts the compiled loop made since ``before`` to each kind's record."""
        d = self._stats - before
        for r, k in enumerate(kinds):
            if k in self.stats:
                st = self.stats[k]
                st.attempted += int(d[r, 0])
                st.refused += int(d[r, 1])
                st.accepted += int(d[r, 2])

    def attempt(self, get_pos: Callable, set_pos: Callable, energy_fn: Callable, *,
                parameters: dict | None = None) -> None:
        """``moves_per_call`` Metropolis proposals on one replica.

        ``get_pos()`` / ``set_pos(p)`` read and write the replica's positions (its own
        frame, nm); ``energy_fn()`` is the engine's potential energy (pN nm), read only by
        the guard.

        Raises
        ------
        RuntimeError
            When the guard finds the local energies and the engine's disagree.
        """
        self._sync_trap(parameters)
        pos = np.array(get_pos(), np.float64, copy=True, order="C")
        check = self.guard_every > 0 and self._calls % self.guard_every == 0
        self._calls += 1
        if check:
            e0 = float(energy_fn())
            t0 = self.energy.total_terms(pos)
        acc0 = self._stats[:, 2].sum()
        terms, absum = self._run(pos, self.moves_per_call)
        if self._stats[:, 2].sum() > acc0:
            set_pos(pos)
        if check:
            self._guard(e0, t0, float(energy_fn()), self.energy.total_terms(pos), terms,
                        absum)

    def _sync_trap(self, parameters: dict | None) -> None:
        """Give the kernels the Context's current trap angle (the protocol sets
        ``trap_angle`` in the Context; the System's default is not it): ``parameters`` are
        the Context's global parameters, which the run layer hands to every call."""
        le = self.energy
        if le.trap_angle is None:
            return
        if parameters is None or "trap_angle" not in parameters:
            raise RuntimeError("BraidMoves needs the Context's trap_angle: call attempt(..., "
                               "parameters=engine.parameters())")
        le.set_trap_angle(parameters["trap_angle"])

    def _guard(self, e0, t0, e1, t1, terms, absum) -> None:
        acc = ", ".join(f"{k} {st.accepted}" for k, st in self.stats.items())
        for name in self.energy.terms:
            k = TERMS.index(name)
            want = t1[name] - t0[name]
            if abs(terms[k] - want) > 1e-9 * (absum + abs(t0[name]) + abs(t1[name])) + 1e-9:
                raise RuntimeError(
                    f"ChainMoves guard: the accepted moves changed term {name!r} by "
                    f"{terms[k]:.10g} pN nm by their local differences, but its total by "
                    f"{want:.10g} pN nm (LocalEnergy.delta and .total disagree; accepted "
                    f"so far: {acc})")
        local = sum(t1.values()) - sum(t0.values())
        diff = abs((e1 - e0) - local)
        self.guard_checks += 1
        self.guard_max_diff = max(self.guard_max_diff, diff)
        tol = self.guard_rel * max(abs(e0), abs(e1)) + self.guard_abs
        if diff > tol:
            per = ", ".join(f"{n} {t1[n] - t0[n]:.6g}" for n in self.energy.terms)
            raise RuntimeError(
                f"ChainMoves guard: this call's moves changed the local energy by "
                f"{local:.10g} pN nm ({per}) but the engine's energy by {e1 - e0:.10g} pN nm "
                f"(|difference| {diff:.3g} > tolerance {tol:.3g} = {self.guard_rel:g} x "
                f"|E| + {self.guard_abs:g}); accepted so far: {acc}. The engine's System "
                "holds a term or parameter the kernels do not reproduce")

    def summary(self) -> dict:
        """Amplitudes, the guard's record and the counts of each kind (as
        :meth:`dnabraid.run.moves.RigidMoves.summary` writes them)."""
        return {"crank_angle_rad": self.crank_angle, "pivot_angle_rad": self.pivot_angle,
                "bead_move_nm": self.bead_nm, "crank_max_beads": self.crank_max,
                "moves_per_call": self.moves_per_call, "guard_checks": self.guard_checks,
                "guard_max_diff_pN_nm": self.guard_max_diff,
                **{k: v.to_dict() for k, v in self.stats.items()}}


class BraidMoves(ChainMoves):
    """Metropolis moves of a braid (:mod:`dnabraid.kernels.braid_moves`): crankshafts inside
    each strand, single-particle moves, the ``shear`` of the top (bead centre and
    attachments translated by d, strand bead k by d k / (beads - 1): the pendulum mode)
    and the ``twist`` (the same weights, turned about the vertical axis through the bead
    centre: the top in the trap, the strands following) and the ``sway`` (each strand turned
    rigidly about its anchor by one rotation about a horizontal axis, the bead centre
    translated with the attachments: the pendulum with the strands' shapes kept) and the
    ``pivot`` (both strands above bead k and the bead centre turned rigidly about the line
    through the two strands' beads k - 1, the centre following the attachments: the
    extension), the ``tilt`` (the bead centre turned about the line through the
    attachments) and the ``stretch`` (both strands raised and straightened together, a
    Metropolis-Hastings move with a constant Jacobian). Moves that would change the
    strands' catenation by more than 0.5 turn (a strand passing the other) are refused.
    The interface and the guard are :class:`ChainMoves`'.

    Parameters
    ----------
    energy : LocalEnergy, Model or System
    chains : two int arrays
        The strands, surface -> attachment.
    fixed : iterable of int
    center : int
        The bead centre (moved by bead, shear and twist moves).
    kT_pN_nm : float
    moves_per_call : int
    crank_angle_rad, bead_move_nm, shear_nm, shear_z_nm, twist_rad, sway_rad, pivot_rad, tilt_rad : float
    stretch_eps : float
        Largest |log lambda| of a stretch move (0 leaves it out).
    stretch_ratio : float or None
        a in mu = lambda^-a; None: <b_z^2> / <b_xy^2> of the strands' bonds at the first
        call after each :meth:`restart` (clipped to [1, 100]), then fixed.
    breathe_eps : float
        Largest |log mu| of a breathe move (the braid opened about its pairs' midpoints,
        bond lengths kept; 0 leaves it out).
    breathe_max_beads : int
        Most pairs in a breathe move's window (>= 2).
        Amplitudes (0 leaves a kind out; ``shear_z_nm`` 0 keeps the shear horizontal).
    crank_max_beads : int
    weights : 9 floats
        Relative probabilities of crankshaft, bead, shear, twist, sway, pivot, tilt,
        stretch, breathe.
    seed, guard_every, guard_rel, guard_abs_pN_nm
        As :class:`ChainMoves`'.
    passage_test : bool
        Decide the topology by :func:`dnabraid.kernels.braid_moves.no_passage` where it
        can (no segment can meet the other strand on the straight path between the two
        states), the Gauss sums only where it cannot; False: the Gauss sums always (the
        same equilibrium; for benchmarks).
    mirror : bool
        Draw the y -> -y mirror of the random numbers (:func:`mirror_random`): the image
        of a mirror-coupled pair (scene key ``mirror = "image"``), whose moves then mirror
        the original's, move by move, as its Brownian noise does.
    """

    def __init__(self, energy, chains, fixed, center: int, kT_pN_nm: float, *,
                 moves_per_call: int, crank_angle_rad: float, bead_move_nm: float,
                 shear_nm: float, shear_z_nm: float = 0.0, twist_rad: float = 0.0,
                 sway_rad: float = 0.0, pivot_rad: float = 0.0, tilt_rad: float = 0.0,
                 stretch_eps: float = 0.0, stretch_ratio: float | None = None,
                 breathe_eps: float = 0.0, breathe_max_beads: int = 40,
                 crank_max_beads: int = 8,
                 weights=(4.0, 4.0, 0.5, 0.5, 1.0, 2.0, 1.0, 2.0, 2.0), seed: int = 1,
                 guard_every: int = 100, guard_rel: float = GUARD_REL,
                 guard_abs_pN_nm: float = GUARD_ABS_PN_NM, passage_test: bool = True,
                 mirror: bool = False):
        if moves_per_call < 1:
            raise ValueError("moves_per_call must be >= 1")
        self.passage_test = bool(passage_test)
        self.mirror = bool(mirror)
        amps = (float(crank_angle_rad), float(bead_move_nm), float(shear_nm),
                float(twist_rad), float(sway_rad), float(pivot_rad), float(tilt_rad),
                float(stretch_eps), float(breathe_eps))
        if min(amps) < 0 or shear_z_nm < 0 or not any(a > 0 for a in amps):
            raise ValueError("move amplitudes must be >= 0, not all 0")
        if amps[0] > math.pi or max(amps[3:7]) > math.pi:
            raise ValueError("crank_angle_rad, twist_rad, sway_rad, pivot_rad and tilt_rad "
                             "must be <= pi")
        if crank_max_beads < 1 or breathe_max_beads < 2:
            raise ValueError("crank_max_beads must be >= 1 and breathe_max_beads >= 2")
        chains = [np.asarray(c, np.int64) for c in chains]
        if len(chains) != 2 or any(len(c) < 2 for c in chains):
            raise ValueError("BraidMoves needs two strands of >= 2 beads")
        w = kind_weights(weights, amps, guard_every)
        self._energy = energy
        self.kT = float(kT_pN_nm)
        self.moves_per_call = int(moves_per_call)
        (self.crank_angle, self.bead_nm, self.shear_nm, self.twist_rad, self.sway_rad,
         self.pivot_rad, self.tilt_rad, self.stretch_eps, self.breathe_eps) = amps
        self.breathe_max = int(breathe_max_beads)
        if stretch_ratio is not None and not stretch_ratio > 0:
            raise ValueError("stretch_ratio must be > 0")
        self.stretch_ratio = None if stretch_ratio is None else float(stretch_ratio)
        self._given_ratio = self.stretch_ratio
        self._chains = chains
        self.shear_z_nm = float(shear_z_nm)
        self.crank_max = int(crank_max_beads)
        self.weights = w / w.sum()
        self._cum = np.cumsum(self.weights)
        self._cum[-1] = 1.0 + 1e-12
        self.seed = int(seed)
        self.guard_every = int(guard_every)
        self.guard_rel = float(guard_rel)
        self.guard_abs = float(guard_abs_pN_nm)
        fixed = {int(i) for i in fixed}
        self.center = int(center)
        self._c_ptr = np.concatenate([[0], np.cumsum([len(c) for c in chains])]).astype(
            np.int64)
        self._c_beads = np.concatenate(chains).astype(np.int64)
        isfixed = np.array([int(i) in fixed for i in self._c_beads], np.int64)
        self._c_fixed = np.concatenate([[0], np.cumsum(isfixed)]).astype(np.int64)
        self._mobile = np.concatenate([self._c_beads[isfixed == 0],
                                       [] if self.center in fixed else [self.center]]
                                      ).astype(np.int64)
        n = int(max(self._c_beads.max(), self.center)) + 1
        self._wgt_n = n
        wgt = np.zeros(n)
        for c in chains:
            wgt[c] = np.arange(len(c)) / (len(c) - 1)
        wgt[self.center] = 1.0
        wgt[list(fixed & set(range(n)))] = 0.0
        self._wgt = wgt
        self.kinds = [k for k, x in zip(BRAID_KINDS, self.weights) if x > 0]
        self.stats = {k: MoveStats() for k in self.kinds}
        self._stats = np.zeros((len(BRAID_KINDS), 3), np.int64)
        self.rng = np.random.default_rng([self.seed, 0])
        self._calls = 0
        self.guard_checks = 0
        self.guard_max_diff = 0.0
        self.catenation = None

    @classmethod
    def for_model(cls, model, **kw) -> BraidMoves:
        """Moves of a built braid model (its chains, fixed beads, bead centre and kT)."""
        return cls(LocalEnergy(model), model.chains, model.fixed, model.bead_center,
                   model.dna.kT, **kw)

    def restart(self, stream: int) -> None:
        """As :meth:`ChainMoves.restart`; a stretch ratio taken from the positions is taken
        again at the next call, so that a segment's moves depend on its own start alone (a
        resumed run then repeats an uninterrupted one to all digits)."""
        super().restart(stream)
        self.stretch_ratio = self._given_ratio

    def _run(self, pos: np.ndarray, n: int) -> tuple[np.ndarray, float]:
        uni = self.rng.random((n, 6))
        gau = self.rng.standard_normal((n, 3))
        if self.mirror:
            uni, gau = mirror_random(self._cum, uni, gau)
        before = self._stats.copy()
        terms, absum, cat = self.run_with(pos, uni, gau)
        self.catenation = float(cat)
        self._tally(before, BRAID_KINDS)
        return terms, float(absum)

    def run_with(self, pos: np.ndarray, uni: np.ndarray, gau: np.ndarray):
        """The compiled loop on ``pos`` (in place) with the given random numbers (uniforms
        (n, 6), Gaussians (n, 3): one proposal per row; mirror studies feed their own);
        returns (accepted change per term, sum of |dE| accepted, catenation). Statistics
        accumulate in the compiled counters, not in :attr:`stats`."""
        le = self.energy
        if le.n != len(self._wgt):
            wgt = np.zeros(le.n)
            wgt[:len(self._wgt)] = self._wgt
            self._wgt = wgt
        terms = np.zeros(NTERMS)
        absum, cat = run_braid_moves(pos, le.params, self._c_ptr, self._c_beads,
                                     self._c_fixed, self._mobile, self._wgt, self.center,
                                     self._cum, self.crank_max, self.crank_angle,
                                     self.bead_nm, self.shear_nm, self.shear_z_nm,
                                     self.twist_rad, self.sway_rad, self.pivot_rad,
                                     self.tilt_rad, self.stretch_eps, self._ratio(pos),
                                     self.breathe_eps, self.breathe_max, self.kT, uni, gau,
                                     self._stats, terms, self.passage_test)
        return terms, absum, cat

    def _ratio(self, pos) -> float:
        """The stretch move's a (fixed at the first call; see the constructor)."""
        if self.stretch_ratio is None:
            num = den = 0.0
            for c in self._chains:
                b = np.diff(np.asarray(pos)[c], axis=0)
                num += float(np.sum(b[:, 2] ** 2))
                den += float(np.sum(b[:, :2] ** 2))
            self.stretch_ratio = float(np.clip(num / max(den, 1e-12), 1.0, 100.0))
        return self.stretch_ratio

    def summary(self) -> dict:
        """Amplitudes, the guard's record and the counts of each kind."""
        return {"crank_angle_rad": self.crank_angle, "bead_move_nm": self.bead_nm,
                "shear_nm": self.shear_nm, "shear_z_nm": self.shear_z_nm,
                "twist_rad": self.twist_rad, "sway_rad": self.sway_rad,
                "pivot_rad": self.pivot_rad, "tilt_rad": self.tilt_rad,
                "stretch_eps": self.stretch_eps, "stretch_ratio": self.stretch_ratio,
                "breathe_eps": self.breathe_eps, "breathe_max_beads": self.breathe_max,
                "crank_max_beads": self.crank_max,
                "moves_per_call": self.moves_per_call, "guard_checks": self.guard_checks,
                "guard_max_diff_pN_nm": self.guard_max_diff,
                **{k: v.to_dict() for k, v in self.stats.items()}}
