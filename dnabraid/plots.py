"""Figures a person would rather look at than read (matplotlib's Figure API; no global
backend switch, so the library never changes a user's matplotlib state)."""

from __future__ import annotations

import os

import numpy as np


def _save(fig, path: str, dpi: int) -> str:
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    FigureCanvasAgg(fig)
    root, ext = os.path.splitext(path)
    tmp = root + ".tmp" + (ext or ".png")
    fig.savefig(tmp, dpi=dpi)
    os.replace(tmp, path)
    return path


def extension_torque_plot(summary: dict, path: str) -> str:
    """Extension and torque against turns, with error bars, to ``path`` (PNG).

    Points whose ``converged`` flag is False (when the summary carries one) are drawn as
    open markers and listed in the title.
    """
    from matplotlib.figure import Figure

    pts = summary["points"]
    n = np.array([p["turns"] for p in pts], float)

    def col(key, what):
        return np.array([p[key][what] if p[key]["mean"] is not None else np.nan for p in pts],
                        float)

    unconv = np.array([p.get("converged") is False for p in pts], bool)
    has_torque = any(p["torque_pN_nm"]["mean"] is not None for p in pts)
    fig = Figure(figsize=(5.5, 6 if has_torque else 3.5))
    axes = fig.subplots(2 if has_torque else 1, 1, sharex=True, squeeze=False)
    ax = axes[0, 0]
    err = col("extension_nm", "ci_halfwidth") if all(
        "ci_halfwidth" in p["extension_nm"] for p in pts) else col("extension_nm", "sem")
    ax.errorbar(n, col("extension_nm", "mean"), yerr=err, fmt="o-", capsize=3)
    if unconv.any():
        ax.plot(n[unconv], col("extension_nm", "mean")[unconv], "o", mfc="white", mec="C3",
                label="not converged")
        ax.legend(fontsize=8)
    ax.set_ylabel("extension (nm)")
    sc = summary.get("scene", {})
    ax.set_title(f"{sc.get('scene', '')}: F = {sc.get('force_pN', '?')} pN, "
                 f"{sc.get('salt_mM', '?')} mM, L = {sc.get('length_nm', '?')} nm", fontsize=9)
    if has_torque:
        ax2 = axes[1, 0]
        ax2.errorbar(n, col("torque_pN_nm", "mean"), yerr=col("torque_pN_nm", "sem"), fmt="s-",
                     color="C3", capsize=3)
        ax2.axhline(0, color="0.7", lw=0.8)
        ax2.set_ylabel("torque (pN nm)")
    axes[-1, 0].set_xlabel("bead turns n")
    fig.tight_layout()
    return _save(fig, path, 120)


def knot_plot(x, summary: dict, path: str) -> str:
    """Side and top views of the relaxed knot (PNG)."""
    from matplotlib.figure import Figure

    x = np.asarray(x)
    fig = Figure(figsize=(10, 5))
    ax = fig.subplots(1, 2)
    for a, (i, j, lab) in zip(ax, ((1, 2, "y-z (loop plane)"), (0, 2, "x-z"))):
        a.plot(x[:, i], x[:, j], "-", lw=1.0)
        a.set_aspect("equal")
        a.set_xlabel(["x", "y", "z"][i] + " (nm)")
        a.set_ylabel("z (nm)")
        a.set_title(lab)
    m = summary["measured"]
    t = summary["theory"]
    fig.suptitle(f"n = {summary['knot_n']}, eps = {summary['eps']:.3f}: R_apex "
                 f"{m['radius_apex_nm']:.1f} nm (theory {t['radius_nm']:.1f}), braid "
                 f"{m['braid_length_nm']:.1f} nm (theory {t['braid_length_nm']:.1f})",
                 fontsize=10)
    fig.tight_layout()
    return _save(fig, path, 110)
