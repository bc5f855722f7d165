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


def sweep_plot(spec, rows: list[dict], path: str) -> str | None:
    """One figure per sweep, from the scene's result columns (PNG).

    A scene with several rows per point (tweezer scenes: one per turn value) gives one
    curve per point of its second result column against its first (extension against
    turns); a scene with one row per point (the knot scene) gives its first varying result
    column against the first numeric grid key, one curve per value of the other keys, with
    its theory column dashed where the scene gives one. Error bars come from the matching
    ``_sem`` column. If the rows hold +n and -n turns and the sweep varies ``alpha`` (or
    has more than one point), a second panel shows the asymmetry z(+n) - z(-n)
    (:func:`dnabraid.analysis.handedness.asymmetry`) against the swept key (``alpha`` if
    swept, else the first numeric grid key).

    Parameters
    ----------
    spec : dnabraid.sweep.SweepSpec
        The sweep (its grid, points and the scene's result columns).
    rows : list of dict
        The gathered rows (:func:`dnabraid.sweep.gather`).
    path : str
        Where to write the figure (written atomically).

    Returns
    -------
    str or None
        ``path``, or None when no point finished or no result column is numeric.
    """
    from matplotlib.figure import Figure

    from .analysis.handedness import asymmetry
    from .sweep.gather import is_number, sem_column
    from .sweep.spec import format_value

    keys = list(spec.grid)
    done = [r for r in rows if r["status"] == "done"]
    if not done:
        return None
    cols = spec.row_columns
    sem_cols = {s for c in cols if (s := sem_column(c, cols))}
    numeric = [c for c in cols if c not in sem_cols
               and all(is_number(r.get(c)) for r in done)]
    counts: dict = {}
    for r in done:
        counts[r["point"]] = counts.get(r["point"], 0) + 1
    per_point = max(counts.values()) > 1
    num_keys = [k for k in spec.grid if all(is_number(v) for v in spec.grid[k])]
    if per_point and numeric:
        xcol = numeric[0]
    else:
        xcol = num_keys[0] if num_keys else None
    ycands = [c for c in numeric if c != xcol]
    varying = [c for c in ycands if len({r[c] for r in done}) > 1]
    ycol = (varying or ycands or [None])[0]
    if ycol is None:
        return None
    asym = asymmetry(rows, keys)
    akey = "alpha" if "alpha" in keys else (num_keys[0] if num_keys else None)
    show_asym = bool(asym) and akey is not None and ("alpha" in keys or len(asym) > 1)
    ncol = 2 if show_asym else 1
    fig = Figure(figsize=(5.2 * ncol, 3.9))
    axes = fig.subplots(1, ncol, squeeze=False)
    ax = axes[0, 0]
    ysem = sem_column(ycol, cols)
    # a theory column beside the measured one (knot: radius_apex_nm, radius_theory_nm)
    theory = next((c for c in numeric if "theory" in c and c != ycol
                   and c.split("_")[0] == ycol.split("_")[0]), None)

    def bars(rs):
        return [(r.get(ysem) or 0) if ysem else 0 for r in rs]

    if per_point:
        for i, p in enumerate(spec.points):
            rs = sorted((r for r in done if r["point"] == p.name), key=lambda r: r[xcol])
            if not rs:
                continue
            label = ", ".join(f"{k}={format_value(v)}" for k, v in p.values.items())
            ax.errorbar([r[xcol] for r in rs], [r[ycol] for r in rs], yerr=bars(rs), fmt="o-",
                        ms=3, capsize=2, label=label, color=f"C{i % 10}")
    else:
        others = [k for k in keys if k != xcol]
        groups: dict = {}
        for r in done:
            groups.setdefault(tuple(format_value(r[k]) for k in others), []).append(r)
        for j, (g, rs) in enumerate(groups.items()):
            if xcol is None:
                xs = [spec.points.index(next(p for p in spec.points if p.name == r["point"]))
                      for r in rs]
            else:
                rs.sort(key=lambda r: r[xcol])
                xs = [r[xcol] for r in rs]
            label = ", ".join(f"{k}={v}" for k, v in zip(others, g)) or None
            ax.errorbar(xs, [r[ycol] for r in rs], yerr=bars(rs), fmt="o-", ms=3, capsize=2,
                        label=label, color=f"C{j % 10}")
            if theory:
                ax.plot(xs, [r[theory] for r in rs], "--", color=f"C{j % 10}", lw=1,
                        label=f"{theory}" + (f" ({label})" if label else ""))
    ax.set_xlabel(xcol or "point")
    ax.set_ylabel(ycol)
    if ax.get_legend_handles_labels()[1]:
        ax.legend(fontsize=7, frameon=False)
    if show_asym:
        ax2 = axes[0, 1]
        others = [k for k in keys if k != akey]
        agroups: dict = {}
        for a in asym:
            agroups.setdefault(tuple(format_value(a[k]) for k in others), []).append(a)
        for j, (g, items) in enumerate(agroups.items()):
            items.sort(key=lambda a: a[akey])
            label = ", ".join(f"{k}={v}" for k, v in zip(others, g)) or None
            ax2.errorbar([a[akey] for a in items], [a["asymmetry_nm"] for a in items],
                         yerr=[a["asymmetry_sem_nm"] for a in items], fmt="s-", capsize=2,
                         label=label, color=f"C{j % 10}")
        ax2.axhline(0, color="0.7", lw=0.8)
        ns = sorted({a["n"] for a in asym})
        ax2.set_xlabel(akey)
        xs = [a[akey] for a in asym]
        if akey == "salt_mM" and min(xs) > 0 and max(xs) >= 10 * min(xs):
            ax2.set_xscale("log")
        ax2.set_ylabel(f"z(+n) - z(-n) (nm), n = {', '.join(f'{n:g}' for n in ns)}")
        if any(g for g in agroups):
            ax2.legend(fontsize=7, frameon=False)
    fig.suptitle(f"sweep {os.path.basename(os.path.normpath(spec.out))}: scene "
                 f"{spec.points[0].scene.name}", fontsize=9)
    fig.tight_layout()
    tmp = path + ".tmp.png"
    fig.savefig(tmp, dpi=110, format="png")
    os.replace(tmp, path)
    return path


def hat_curve_plot(points: list, result: dict, path: str, title: str = "") -> str:
    """The hat curve (extension and twist torque against turns) beside rod theory, to
    ``path`` (PNG): the Moroz-Nelson torque line below buckling, the plateau torque, the
    classical buckling torque sqrt(2 kT A F) and the two-phase slope -pi x tau / g drawn
    through the buckled points' mean (:func:`dnabraid.analysis.hat_curve.hat_curve`).
    Unconverged points are open markers."""
    from matplotlib.figure import Figure

    n = np.array([p["turns"] for p in points], float)
    z = np.array([p["extension_nm"]["mean"] for p in points], float)
    zs = np.array([p["extension_nm"]["sem"] for p in points], float)
    t = np.array([p["twist_torque_pN_nm"]["mean"] for p in points], float)
    ts = np.array([p["twist_torque_pN_nm"]["sem"] for p in points], float)
    conv = np.array([p.get("converged") is not False for p in points], bool)
    fig = Figure(figsize=(5.5, 6))
    ax1, ax2 = fig.subplots(2, 1, sharex=True)
    for ax, y, e in ((ax1, z, zs), (ax2, t, ts)):
        ax.errorbar(n[conv], y[conv], e[conv], fmt="o", color="C0", label="simulation")
        if (~conv).any():
            ax.errorbar(n[~conv], y[~conv], e[~conv], fmt="o", mfc="none", color="C0",
                        label="not converged")
    nb = result.get("n_buckle", float("nan"))
    if "slope_two_phase" in result and np.isfinite(nb):
        b = n >= nb
        n0, z0 = float(np.mean(n[b])), float(np.mean(z[b]))
        nn = np.linspace(n[b].min(), n[b].max(), 2)
        ax1.plot(nn, z0 + result["slope_two_phase"] * (nn - n0), "--", color="C3",
                 label=f"two-phase slope {result['slope_two_phase']:.0f} nm/turn")
    nn = np.linspace(0, n.max(), 50)
    kT, L = result["kT"], result.get("L")
    if L:
        ax2.plot(nn, 2 * np.pi * kT * result["ceff_theory"] * nn / L, ":", color="C2",
                 label="Moroz-Nelson C_eff")
    ax2.axhline(result["gamma_b_theory"], color="C1", ls="-.", label="sqrt(2 kT A F)")
    if "plateau_torque" in result:
        ax2.axhline(result["plateau_torque"], color="C3", ls="--", label="plateau (simulated)")
    ax1.set_ylabel("extension (nm)")
    ax2.set_ylabel("twist torque (pN nm)")
    ax2.set_xlabel("turns n")
    ax1.legend(fontsize=7)
    ax2.legend(fontsize=7)
    if title:
        ax1.set_title(title, fontsize=8)
    fig.tight_layout()
    return _save(fig, path, 120)
