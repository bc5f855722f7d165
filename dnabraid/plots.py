"""Figures a person would rather look at than read."""

from __future__ import annotations

import os


def extension_torque_plot(summary: dict, path: str) -> str:
    """Extension and torque against turns, with SEM error bars, to ``path`` (PNG)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    pts = summary["points"]
    n = [p["turns"] for p in pts]

    def col(key, what):
        return [p[key][what] if p[key]["mean"] is not None else float("nan") for p in pts]

    has_torque = any(p["torque_pN_nm"]["mean"] is not None for p in pts)
    fig, axes = plt.subplots(2 if has_torque else 1, 1, figsize=(5.5, 6 if has_torque else 3.5),
                             sharex=True, squeeze=False)
    ax = axes[0, 0]
    ax.errorbar(n, col("extension_nm", "mean"), yerr=col("extension_nm", "sem"), fmt="o-",
                capsize=3)
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
    tmp = path + ".tmp.png"
    fig.savefig(tmp, dpi=120)
    plt.close(fig)
    os.replace(tmp, path)
    return path
