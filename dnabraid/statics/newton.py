"""Damped Newton minimisation of bead-rod energies at zero temperature, with saddle escape.

One solver (:func:`minimize`) for the zero-temperature bead problems of this package (the
open knot, :mod:`dnabraid.statics.open_knot`; the closed braids,
:mod:`dnabraid.statics.closed_braid`), and the Hessian pieces they share: the 3x3 blocks
of a pair spring (:func:`pair_blocks`) and of a hinge (:func:`hinge_blocks`), the sparse
assembler that places them (:class:`HessianAssembler`), and the lowest eigenmode of a
Hessian (:func:`lowest_mode`).

Why Newton
----------
Plain L-BFGS (OpenMM's ``LocalEnergyMinimizer``, scipy's) does not reach these minima in
reasonable time: the slow mode is the rod sliding along itself through a contact, which in
Cartesian coordinates is a curved valley (measured on a 737-bead trefoil: 18000 L-BFGS
iterations moved its loop by < 1 %). Newton's method on the exact sparse Hessian follows
the valley and converges in tens of iterations.

The iteration
-------------
Each step solves ``(H + mu I) p = -g`` on the free coordinates (Levenberg damping ``mu``;
Nocedal & Wright, *Numerical Optimization*, 2nd ed. 2006, Sec. 10.3), caps the largest
coordinate change at ``max_step`` (never across the rod), and backtracks (halving) until
the Armijo condition ``E(x + t p) <= E(x) + 1e-4 t p.g`` holds (ibid., Eq. 3.4). A step
that is not a descent direction, or that no backtracking makes acceptable, raises ``mu``
ten-fold; an accepted one lowers it three-fold (or, with ``adaptive_damping``, raises it
by ``4/t`` after a cut step ``t < 1``, Levenberg-Marquardt style). ``H`` is Gauss-Newton
(the negative part of compressed springs dropped) far from the minimum and exact below
``exact_below``.

Newton's method is attracted by saddles as much as by minima: at a stationary point the
lowest eigenvalue of the exact Hessian is computed (``lowest_mode``) and, while it is
negative, the configuration is displaced along that mode (by ``escape_step`` at its
largest coordinate, to whichever side has the lower energy) and the iteration resumes.
"""

from __future__ import annotations

import dataclasses
import logging
import math
from collections.abc import Callable

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..errors import DnabraidError

__all__ = [
    "HessianAssembler",
    "NewtonError",
    "NewtonSettings",
    "hinge_blocks",
    "lowest_mode",
    "minimize",
    "pair_blocks",
]

log = logging.getLogger(__name__)


class NewtonError(DnabraidError, RuntimeError):
    """The Newton iteration failed (non-finite force, a saddle it cannot leave, an
    eigensolver failure); the message names the iteration."""


# -- Hessian blocks ----------------------------------------------------------------------------

def pair_blocks(d, r, k: float, r0: float, gauss_newton: bool):
    """Gradient and 3x3 Hessian of ``U = k/2 (r - r0)^2`` with respect to the pair vector.

    Parameters
    ----------
    d : ndarray, shape (m, 3)
        Pair vectors ``x_j - x_i`` (nm).
    r : ndarray, shape (m,)
        Their lengths.
    k, r0 : float
        Spring constant (pN/nm) and rest length (nm).
    gauss_newton : bool
        Drop the negative transverse stiffness ``k (r - r0) / r`` of a compressed spring
        (``r < r0``), which keeps the Hessian closer to positive definite.

    Returns
    -------
    g : ndarray, shape (m, 3)
        ``dU/dd``.
    H : ndarray, shape (m, 3, 3)
        ``d^2U/dd^2 = k u u^T + k (r - r0)/r (I - u u^T)``, ``u = d / r``.
    """
    u = d / r[:, None]
    g = (k * (r - r0))[:, None] * u
    uu = u[:, :, None] * u[:, None, :]
    fac = k * (r - r0) / r
    if gauss_newton:
        fac = np.maximum(fac, 0.0)
    return g, k * uu + fac[:, None, None] * (np.eye(3) - uu)


def hinge_blocks(u, v, kappa: float):
    """Gradient and exact Hessian blocks of the hinge energy ``U = kappa (1 - c)``.

    ``c = u.v / (|u| |v|)`` is the cosine of the angle between consecutive bond vectors.

    Parameters
    ----------
    u, v : ndarray, shape (m, 3)
        Bond vectors ``x1 - x0`` and ``x2 - x1`` of each hinge.
    kappa : float
        Hinge stiffness (pN nm; ``B / b`` for bending stiffness ``B`` and bond length ``b``).

    Returns
    -------
    Gu, Gv : ndarray, shape (m, 3)
        ``dU/du``, ``dU/dv``.
    Huu, Hvv, Huv : ndarray, shape (m, 3, 3)
        ``d^2U/du^2``, ``d^2U/dv^2``, ``d^2U/du dv``.
    """
    a, bv = np.linalg.norm(u, axis=1), np.linalg.norm(v, axis=1)
    uh, vh = u / a[:, None], v / bv[:, None]
    c = np.sum(uh * vh, axis=1)
    gu = (vh - c[:, None] * uh) / a[:, None]
    gv = (uh - c[:, None] * vh) / bv[:, None]
    I3 = np.eye(3)

    def outer(p_, q_):
        return p_[:, :, None] * q_[:, None, :]

    Huu = -(outer(uh, gu) + outer(gu, uh)) / a[:, None, None] - \
        (c / a**2)[:, None, None] * (I3 - outer(uh, uh))
    Hvv = -(outer(vh, gv) + outer(gv, vh)) / bv[:, None, None] - \
        (c / bv**2)[:, None, None] * (I3 - outer(vh, vh))
    Huv = (I3 - outer(uh, uh) - outer(vh, vh) + c[:, None, None] * outer(uh, vh)) / \
        (a * bv)[:, None, None]
    # U = -kappa c (+ const): dU/du = -kappa gu ...
    return -kappa * gu, -kappa * gv, -kappa * Huu, -kappa * Hvv, -kappa * Huv


class HessianAssembler:
    """Gradient ``g`` (N, 3) and sparse Hessian (3N x 3N) of a sum of bead-pair and hinge
    terms, accumulated block by block.

    Parameters
    ----------
    n_beads : int
        Number of beads N.
    """

    def __init__(self, n_beads: int):
        self.N = int(n_beads)
        self.g = np.zeros((self.N, 3))
        self.rows, self.cols, self.vals = [], [], []

    def block(self, a, c, blk) -> None:
        """Add the 3x3 blocks ``blk`` (m, 3, 3) at bead rows ``a`` and bead columns ``c``."""
        ia = (3 * a)[:, None, None] + np.arange(3)[None, :, None]
        ic = (3 * c)[:, None, None] + np.arange(3)[None, None, :]
        self.rows.append(np.broadcast_to(ia, blk.shape).ravel())
        self.cols.append(np.broadcast_to(ic, blk.shape).ravel())
        self.vals.append(blk.ravel())

    def diagonal(self, idx, values) -> None:
        """Add ``values`` on the diagonal at flat coordinates ``idx``."""
        self.rows.append(np.asarray(idx))
        self.cols.append(np.asarray(idx))
        self.vals.append(np.asarray(values, float))

    def pair(self, i, j, gd, Hd) -> None:
        """Add pair terms ``U(d)``, ``d = x_j - x_i``, given ``dU/dd`` and ``d^2U/dd^2``
        (as from :func:`pair_blocks`)."""
        np.add.at(self.g, j, gd)
        np.add.at(self.g, i, -gd)
        for a, sa in ((i, -1.0), (j, 1.0)):
            for c, sc in ((i, -1.0), (j, 1.0)):
                self.block(a, c, sa * sc * Hd)

    def hinges(self, x, hinges, kappa: float) -> None:
        """Add ``U = kappa (1 - c)`` for each hinge ``(i0, i1, i2)`` (rows of ``hinges``),
        ``c`` the cosine between ``x[i1] - x[i0]`` and ``x[i2] - x[i1]``: gradient and exact
        Hessian (:func:`hinge_blocks`)."""
        i0, i1, i2 = hinges[:, 0], hinges[:, 1], hinges[:, 2]
        u, v = x[i1] - x[i0], x[i2] - x[i1]
        Gu, Gv, Huu, Hvv, Huv = hinge_blocks(u, v, kappa)
        np.add.at(self.g, i0, -Gu)
        np.add.at(self.g, i1, Gu - Gv)
        np.add.at(self.g, i2, Gv)
        idx = (i0, i1, i2)
        # x-derivatives: du/dx0 = -1, du/dx1 = +1, dv/dx1 = -1, dv/dx2 = +1
        Ju = (-1.0, 1.0, 0.0)
        Jv = (0.0, -1.0, 1.0)
        HvuT = np.transpose(Huv, (0, 2, 1))
        for A in range(3):
            for C in range(3):
                blk = (Ju[A] * Ju[C]) * Huu + (Jv[A] * Jv[C]) * Hvv + \
                    (Ju[A] * Jv[C]) * Huv + (Jv[A] * Ju[C]) * HvuT
                self.block(idx[A], idx[C], blk)

    def matrix(self) -> sp.csr_matrix:
        """The Hessian accumulated so far (CSR, duplicates summed)."""
        n3 = 3 * self.N
        if not self.vals:
            return sp.csr_matrix((n3, n3))
        return sp.coo_matrix((np.concatenate(self.vals),
                              (np.concatenate(self.rows), np.concatenate(self.cols))),
                             shape=(n3, n3)).tocsr()


# -- lowest mode -------------------------------------------------------------------------------

def lowest_mode(H, *, shift: float, free=None, k: int = 1, exclude=()):
    """Lowest eigenvalue and eigenvector of a sparse symmetric Hessian.

    Parameters
    ----------
    H : sparse matrix, shape (n, n)
        The (exact) Hessian.
    shift : float
        Shift-invert about ``-shift`` (ARPACK ``eigsh(sigma=-shift)``): a little below the
        most negative eigenvalue expected.
    free : ndarray of int, optional
        The coordinates the eigenproblem is restricted to (the others held); default all.
    k : int
        Number of eigenpairs computed (more than one when ``exclude`` may remove some).
    exclude : sequence of ndarray, shape (n,)
        Unit vectors (zero modes, e.g. a translation) whose eigenvectors are dropped:
        those with overlap ``|v . e| >= 0.9``.

    Returns
    -------
    lam : float
        The lowest remaining eigenvalue.
    vec : ndarray, shape (n,)
        Its eigenvector (zero on held coordinates).

    Raises
    ------
    NewtonError
        When ARPACK fails or every computed mode is excluded.
    """
    n = H.shape[0]
    A = H.tocsc() if free is None else H[free][:, free].tocsc()
    try:
        lam, vec = spla.eigsh(A, k=k, sigma=-shift, which="LM")
    except Exception as exc:  # noqa: BLE001 - ARPACK failures are reported, not fatal
        raise NewtonError(f"could not compute the Hessian's lowest mode: {exc}") from exc
    if free is not None:
        full = np.zeros((n, vec.shape[1]))
        full[free] = vec
        vec = full
    keep = np.ones(len(lam), bool)
    for e in exclude:
        keep &= np.abs(vec.T @ e) < 0.9
    if not keep.any():
        raise NewtonError(f"all {k} lowest modes of the Hessian are excluded zero modes")
    lam, vec = lam[keep], vec[:, keep]
    i = int(np.argmin(lam))
    return float(lam[i]), vec[:, i]


# -- the solver --------------------------------------------------------------------------------

@dataclasses.dataclass(frozen=True)
class NewtonSettings:
    """Tolerances and damping of :func:`minimize` (forces pN, lengths nm, stiffness pN/nm).

    Attributes
    ----------
    gtol : float
        Stationary when the largest gradient component (all coordinates) is below this.
    max_step : float
        Largest coordinate change of one Newton step.
    mu_start : float
        Levenberg damping at the start and after each saddle escape.
    mu_min : float
        Smallest damping.
    escape_step : float
        Largest coordinate displacement of a saddle escape.
    saddle_tol : float
        A stationary point is a saddle when its lowest curvature is below ``-saddle_tol``.
    max_iter : int
        Newton iterations at most.
    max_escapes : int
        Saddle escapes at most (then :class:`NewtonError`).
    max_damping_tries : int
        Damping increases tried per iteration before the step is given up.
    max_halvings : int
        Backtracking halvings per damping.
    exact_below : float or None
        Use the exact Hessian (not Gauss-Newton) once the largest gradient component is
        below this; ``None``: Gauss-Newton throughout.
    adaptive_damping : bool
        After an accepted step cut to ``t < 1``, raise the damping by ``4/t`` (a soft,
        non-quadratic direction) instead of lowering it three-fold.
    stall_limit : int or None
        ``None``: stop at the first iteration that no damping makes descend. An integer
        ``n``: count such iterations, and accepted steps that change the energy by less
        than 1e-14 of it, and treat the point as stationary (saddle check, then stop)
        after ``n`` in a row; it then counts as converged if its gradient is below
        ``100 gtol`` (the energy cannot resolve a smaller one).
    """

    gtol: float
    max_step: float
    mu_start: float
    mu_min: float
    escape_step: float
    saddle_tol: float = 0.0
    max_iter: int = 2000
    max_escapes: int = 200
    max_damping_tries: int = 30
    max_halvings: int = 20
    exact_below: float | None = None
    adaptive_damping: bool = False
    stall_limit: int | None = None


def minimize(x0, energy: Callable, gradient_hessian: Callable, settings: NewtonSettings, *,
             pinned=None, lowest_mode: Callable | None = None, progress=None) -> dict:
    """Damped Newton minimisation with saddle escape (see the module docstring).

    Parameters
    ----------
    x0 : ndarray, shape (N, 3)
        Start (nm).
    energy : callable
        ``energy(x) -> float`` (pN nm).
    gradient_hessian : callable
        ``gradient_hessian(x, gauss_newton) -> (g, H)``: the gradient, shape (3N,), and the
        sparse Hessian (3N x 3N), Gauss-Newton when ``gauss_newton`` is true.
    settings : NewtonSettings
        Tolerances and damping.
    pinned : array of int, optional
        Flat coordinates held at their start values (e.g. six that remove the rigid-body
        modes); the gradient test still covers all coordinates.
    lowest_mode : callable, optional
        ``lowest_mode(x) -> (lam, vec)``: lowest curvature (pN/nm) and its mode (3N,) of
        the exact Hessian, on the free coordinates. ``None``: no saddle check.
    progress : callable, optional
        Called as ``progress(iteration, largest_gradient_component)``.

    Returns
    -------
    dict
        ``x``, ``iterations``, ``max_force_pN`` (largest gradient component at the last
        evaluation), ``energy_pN_nm``, ``converged``, ``saddle_escapes``,
        ``lowest_curvature_pN_per_nm`` (last saddle check; ``None`` if none ran).

    Raises
    ------
    NewtonError
        On a non-finite gradient, or after ``max_escapes`` escapes.
    """
    s = settings
    x = np.asarray(x0, float).copy()
    n = x.size
    free = None if pinned is None else np.setdiff1d(np.arange(n), pinned)
    E = energy(x)
    mu = s.mu_start
    gmax = math.inf
    escapes = 0
    fails = 0
    lam = None
    it = 0
    for it in range(1, s.max_iter + 1):
        g_full, H = gradient_hessian(x, True)
        gmax = float(np.abs(g_full).max())
        if not math.isfinite(gmax):
            raise NewtonError(f"non-finite force at Newton iteration {it}")
        if progress:
            progress(it, gmax)
        stalled = s.stall_limit is not None and fails >= s.stall_limit
        if gmax < s.gtol or stalled:
            if lowest_mode is None:
                break
            lam, vec = lowest_mode(x)
            if lam >= -s.saddle_tol:
                break
            escapes += 1
            if escapes > s.max_escapes:
                raise NewtonError(f"still at a saddle (curvature {lam:.3g} pN/nm) after "
                                  f"{s.max_escapes} escapes at Newton iteration {it}")
            v = vec.reshape(x.shape) * (s.escape_step / np.abs(vec).max())
            E, sign = min((energy(x + sg * v), sg) for sg in (1.0, -1.0))
            x = x + sign * v
            mu, fails = s.mu_start, 0
            continue
        exact = s.exact_below is not None and gmax < s.exact_below
        if exact:
            _, H = gradient_hessian(x, False)
        if free is None:
            g, Hf = g_full, H
        else:
            g, Hf = g_full[free], H[free][:, free]
        eye = sp.identity(Hf.shape[0], format="csr")
        accepted = False
        for _ in range(s.max_damping_tries):
            try:
                step = spla.spsolve((Hf + mu * eye).tocsc(), -g)
            except RuntimeError:
                step = None
            if step is None or not np.all(np.isfinite(step)) or step @ g >= 0:
                mu = max(10.0 * mu, s.mu_min)
                continue
            smax = float(np.abs(step).max())
            t = min(1.0, s.max_step / smax)  # never jump across the rod
            full = np.zeros(n)
            for _ls in range(s.max_halvings):
                if free is None:
                    xn = x + (t * step).reshape(x.shape)
                else:
                    full[free] = t * step
                    xn = x + full.reshape(x.shape)
                En = energy(xn)
                if En <= E + 1e-4 * t * (step @ g):
                    accepted = True
                    break
                t *= 0.5
            if accepted:
                dE = En - E
                log.debug("it %d E %.17g dE %.3g t %.3g mu %.3g smax %.3g exact %s", it, En,
                          dE, t, mu, smax, exact)
                if s.stall_limit is not None:
                    fails = fails + 1 if abs(dE) <= 1e-14 * abs(E) else 0
                x, E = xn, En
                if s.adaptive_damping and t != 1.0:
                    mu = max(mu * 4.0 / t, s.mu_min)
                else:
                    mu = max(mu / 3.0, s.mu_min)
                break
            mu = max(10.0 * mu, s.mu_min)
        if not accepted:
            if s.stall_limit is None:
                break
            fails += 1  # no descent left within round-off: a (numerically) stationary point
    stalled = s.stall_limit is not None and fails >= s.stall_limit
    return {"x": x, "iterations": it, "max_force_pN": gmax, "energy_pN_nm": E,
            "converged": gmax < s.gtol or (stalled and gmax < 1e2 * s.gtol),
            "saddle_escapes": escapes, "lowest_curvature_pN_per_nm": lam}
