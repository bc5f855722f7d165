"""Replica exchange over the pulling force for a buckled braid (issue "Converged at the
scale of the experiment": the points past the braid's buckling).

docs/validation.md 2.3r: a 2 x 100 nm braid at 2 pN buckles between 1.5 and 2 turns, and
past it the replicas sit in buckled states of different axis writhe (n = 3: 0.60 against
0.80) that 3e5 steps with moves rarely exchange: NOT CONVERGED. A replica-exchange ladder
over the trap angle (the plectoneme's ``sampler = ladder``) needs a map that adds
catenation to a state; for the braid every such map tried changes the stiff bonds'
lengths by thousands of kT (docs/validation.md 2.3s). A ladder over the force needs no
map: all rungs hold the same catenation (one trap angle), a swap exchanges two states as
they are, and only the pull term changes (:class:`dnabraid.run.ladder.ForceLadder`,
acceptance min(1, exp(-(F_k+1 - F_k)(z_k - z_k+1) / kT))). Rungs at forces where the
buckled states exchange fast pass their states to the others.

Per ladder (replica r = 0 ... R-1): every rung starts from its own built braid at the
catenation (the braid scene's overdispersed two-ply, seed 1000 r + k + seed), is
equilibrated alone (``--rung-moves``), then ``--eq-rounds`` rounds with swaps and
``--rounds`` sampling rounds (``--round-moves`` moves per rung, then swaps of even or odd
neighbour pairs); after every round each rung's state gives a sample of the braid scene's
observables (extension, trap and spread torque, catenation), every ``--frame-every``
rounds the braid axis's writhe Wr_ax and the strands' winding about it
(workflows/braid_buckling.py ``split_catenation``). Per rung the R ladders are judged as
independent replicas by the braid scene's own rule (``dnabraid.run.summary.point_summary``:
split R-hat <= 1.05, ESS >= 100 on extension and torque; the torque identity) and, as the
buckled state is the slow variable, by the same rule on the axis writhe Wr_ax.

Usage:
    python workflows/braid_force_ladder.py run --turns 2.5 [--forces 0.5 0.8 1.25 2 3 ...]
    python workflows/braid_force_ladder.py report
Per ladder: <work>/<tag>/ladder_rNN.npz (resumed: finished ladders are not rerun); per run
workflows/results/braid_force_ladder_<tag>.json; all runs: braid_force_ladder.{md,png}.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import multiprocessing as mp
import os
import pathlib
import sys
import time

import numpy as np

HERE = pathlib.Path(__file__).resolve().parent
RESULTS = HERE / "results"
sys.path.insert(0, str(HERE))


def tag_of(a) -> str:
    # the rung count is part of the tag: two ladders over the same range with different
    # rungs are different runs (a 9-rung run once "resumed" from 7-rung files)
    return (f"L{a.length:g}_n{a.turns:g}_salt{a.salt:g}_F{a.forces[0]:g}-{a.forces[-1]:g}"
            f"x{len(a.forces)}_seed{a.seed}")


def base_scene(a, seed: int):
    """The braid scene of a ladder (its starts, observables, move settings and verdict
    rule); mc_moves 0: the ladder builds its own moves (:func:`braid_moves`), so the
    scene's hybrid moves are not built at all."""
    from dnabraid.scenes import make_scene

    return make_scene("braid", {"length_nm": a.length, "force_pN": a.forces[0],
                                "salt_mM": a.salt, "tether_separation_nm": a.separation,
                                "turns": [a.turns], "seed": seed, "mc_moves": 0})


def braid_moves(scene, model, n_moves: int):
    """The braid scene's Metropolis moves (its amplitudes and mix) on the model's
    LocalEnergy."""
    from dnabraid.run.chain_moves import BraidMoves

    return BraidMoves.for_model(model, moves_per_call=n_moves, **scene.move_settings())


def run_ladder(job) -> str:
    """One ladder (replica r): returns the path of its .npz."""
    a, r, path = job
    if os.path.exists(path):
        have = np.load(path)["forces"]
        if len(have) != len(a.forces) or not np.allclose(have, a.forces):
            raise RuntimeError(f"{path} holds a ladder over {list(have)} pN, not the "
                               f"requested {list(a.forces)}: remove it or use --work")
        return path
    from braid_buckling import split_catenation

    from dnabraid.observables import ObserveContext, columns_of
    from dnabraid.run.ladder import ForceLadder
    from dnabraid.run.segments import observe_values

    if getattr(a, "pin", False):  # one core per ladder (workers of cmd_run only)
        try:
            os.sched_setaffinity(0, {r % os.cpu_count()})
        except (AttributeError, OSError):
            pass
    t0 = time.time()
    seed = a.seed + 1000 * r
    scene = base_scene(a, seed)
    model = scene.build()
    mv = braid_moves(scene, model, a.round_moves)
    theta = 2 * math.pi * a.turns
    lad = ForceLadder(mv, a.forces, theta, model.dna.kT, seed=seed)
    K = len(a.forces)
    for k in range(K):  # every rung from its own built start, equilibrated alone
        start = dataclasses.replace(scene, seed=seed + k).built_start(model, a.turns)
        lad.set_rung(k)
        lad.pos[k], _ = mv.run(start, a.rung_moves)
    for _ in range(a.eq_rounds):
        lad.round(a.round_moves)
    obs = [scene.observables(model) for _ in range(K)]
    ctx = ObserveContext(trap_turns=a.turns)
    for o, p in zip(obs, lad.pos):
        for ob in o:
            ob.reset(a.turns, p)
    cols = columns_of(obs[0], "sample")
    samples = {c: np.zeros((K, a.rounds)) for c in cols}
    nf = a.rounds // a.frame_every
    frames = {c: np.zeros((K, nf)) for c in ("wr_axis", "tw_braid", "catenation")}
    # every rung's positions at the writhe frames (float32, nm): the buckled states
    # themselves, for inspection (a 2 x 100 nm ladder of 5 rungs: ~2 MB)
    pos_frames = np.zeros((K, nf) + np.shape(lad.pos[0]), np.float32)
    b1, b2 = model.chains
    acc0, try0 = lad.accepted.copy(), lad.tries.copy()
    trips0 = lad.round_trips
    for i in range(a.rounds):
        lad.round(a.round_moves)
        for k in range(K):
            v, msg = observe_values(obs[k], lad.pos[k], ctx, False)
            if msg:
                raise RuntimeError(f"ladder {r}, rung F = {a.forces[k]:g} pN, round {i}: {msg}")
            for c in cols:
                samples[c][k, i] = v[c]
            if (i + 1) % a.frame_every == 0:
                j = (i + 1) // a.frame_every - 1
                wr, ca = split_catenation(lad.pos[k][b1], lad.pos[k][b2])
                frames["wr_axis"][k, j] = wr
                frames["catenation"][k, j] = ca
                frames["tw_braid"][k, j] = ca - wr
                pos_frames[k, j] = lad.pos[k]
        if (i + 1) % max(1, a.rounds // 10) == 0:  # progress: every tenth of the rounds
            print(f"    ladder {r}: {i + 1}/{a.rounds} rounds, {time.time() - t0:.0f} s, "
                  f"swap acceptance {[round(x, 2) for x in lad.acceptance()]}", flush=True)
    acc = (lad.accepted - acc0) / np.maximum(lad.tries - try0, 1)
    out = {f"s_{c}": x for c, x in samples.items()}
    out.update({f"f_{c}": x for c, x in frames.items()})
    out.update(positions=pos_frames, forces=np.array(a.forces), swap_acceptance=acc,
               round_trips=np.array(lad.round_trips - trips0),
               who=np.asarray(lad.trace[-a.rounds:], np.int16),
               wall_s=np.array(time.time() - t0))
    tmp = path + ".tmp.npz"
    np.savez_compressed(tmp, **out)
    os.replace(tmp, path)
    return path


def summarise(a, paths) -> dict:
    """Per rung: the scene's point summary of the R ladders (extension, torque, verdict),
    the axis writhe across ladders, swap acceptance and round trips."""
    from dnabraid.observables import columns_of
    from dnabraid.run import summary as run_summary

    scene = base_scene(a, a.seed)
    model = scene.build()
    columns = {c: col for ob in scene.observables(model) for c, col in ob.columns.items()}
    data = [dict(np.load(p)) for p in paths]
    rule = scene.verdict_rule()
    rows = []
    for k, F in enumerate(a.forces):
        reps = []
        for d in data:
            s = {c[2:]: d[c][k] for c in d if c.startswith("s_")}
            s["step"] = np.arange(len(s["extension_nm"]))
            f = {c[2:]: d[c][k] for c in d if c.startswith("f_") and c != "f_catenation"}
            f["step"] = np.arange(len(f["wr_axis"]))
            reps.append((s, f))
        pt = run_summary.point_summary({"force_pN": F}, reps, columns, rule)
        ident = dataclasses.replace(scene, force_pN=F).torque_identity(reps)
        wr = pt.get("wr_axis") or {}
        if pt["converged"] and not wr.get("converged"):
            # the buckled state (the axis writhe) is the slow variable: an extension that
            # agrees across ladders whose states differ is not converged
            pt["converged"] = False
            pt["convergence_reason"] = "wr_axis: " + str(wr.get("reason"))
        row = {"force_pN": F, "converged": pt["converged"],
               "reason": pt["convergence_reason"],
               "torque_identity": ident}
        for c in ("extension_nm", "torque_pN_nm", "torque_spread_pN_nm", "catenation",
                  "wr_axis", "tw_braid"):
            v = pt.get(c)
            if isinstance(v, dict) and v.get("mean") is not None:
                row[c] = {x: v.get(x) for x in ("mean", "sem", "rhat", "ess",
                                                "replica_means", "converged")}
        rows.append(row)
    acc = np.mean([d["swap_acceptance"] for d in data], axis=0)
    return {"tag": tag_of(a), "length_nm": a.length, "turns": a.turns, "salt_mM": a.salt,
            "tether_separation_nm": a.separation, "forces_pN": list(a.forces),
            "replicas": len(paths), "rounds": a.rounds, "round_moves": a.round_moves,
            "eq_rounds": a.eq_rounds, "rung_moves": a.rung_moves,
            "frame_every": a.frame_every, "seed": a.seed,
            "swap_acceptance": [float(x) for x in acc],
            "round_trips": [int(d["round_trips"]) for d in data],
            "wall_s_per_ladder": [float(d["wall_s"]) for d in data],
            "moves_per_ladder": int(len(a.forces) * a.round_moves
                                    * (a.rounds + a.eq_rounds) + len(a.forces) * a.rung_moves),
            "rows": rows}


def cmd_run(a) -> None:
    tag = tag_of(a)
    a.pin = True
    work = pathlib.Path(a.work) / tag
    work.mkdir(parents=True, exist_ok=True)
    jobs = [(a, r, str(work / f"ladder_r{r:02d}.npz")) for r in range(a.replicas)]
    t0 = time.time()
    done = 0
    print(f"{a.replicas} force ladders of {len(a.forces)} rungs at n = {a.turns:g} "
          f"({a.workers} worker(s)) -> {work}", flush=True)
    with mp.get_context("spawn").Pool(a.workers) as pool:
        for p in pool.imap_unordered(run_ladder, jobs):
            done += 1
            print(f"  ladder {done}/{a.replicas} done ({time.time() - t0:.0f} s): {p}",
                  flush=True)
    res = summarise(a, [j[2] for j in jobs])
    res["wall_s_this_invocation"] = time.time() - t0  # ladders already done are not rerun
    RESULTS.mkdir(exist_ok=True)
    out = RESULTS / f"braid_force_ladder_{tag}.json"
    out.write_text(json.dumps(res, indent=1) + "\n")
    print(render([res]))
    print(f"wrote {out}")


def _pm(v, digits=2):
    if not v:
        return "-"
    return f"{v['mean']:.{digits}f} +- {v['sem']:.{digits}f}"


def render(results: list[dict]) -> str:
    lines = ["# Braids past buckling by replica exchange over the force", "",
             "`python workflows/braid_force_ladder.py run ...` "
             "(docs/validation.md 2.3s). Per rung the R independent ladders are judged as "
             "replicas by the braid scene's rule (R-hat <= 1.05, ESS >= 100 on extension "
             "and torque, the torque identity) and by the same rule on Wr_ax, the slow "
             "variable. Wr_ax: writhe of the braid axis (strands' "
             "midpoint curve); errors are standard errors across ladders.", ""]
    for res in results:
        lines += [f"## 2 x {res['length_nm']:g} nm, n = {res['turns']:g}, "
                  f"{res['salt_mM']:g} mM, tethers {res['tether_separation_nm']:g} nm",
                  "",
                  f"{res['replicas']} ladders x {len(res['forces_pN'])} rungs, "
                  f"{res['rounds']} rounds of {res['round_moves']} moves per rung "
                  f"(+ {res['eq_rounds']} with swaps, {res['rung_moves']} alone first); "
                  f"{res['moves_per_ladder']:.3g} moves per ladder; wall per ladder "
                  + ", ".join(f"{w:.0f}" for w in res["wall_s_per_ladder"])
                  + " s (one core each); round trips per ladder "
                  + ", ".join(str(t) for t in res["round_trips"]) + ".", "",
                  "| F (pN) | extension (nm) | R-hat, ESS | torque (pN nm) | R-hat, ESS | "
                  "Wr_ax | Wr_ax per ladder | swap acc. to next | verdict |",
                  "|---|---|---|---|---|---|---|---|---|"]
        for k, row in enumerate(res["rows"]):
            z, t, w = row.get("extension_nm"), row.get("torque_pN_nm"), row.get("wr_axis")
            acc = res["swap_acceptance"][k] if k < len(res["swap_acceptance"]) else None
            lines.append(
                f"| {row['force_pN']:g} | {_pm(z)} | "
                f"{z['rhat']:.3f}, {z['ess']:.0f} | {_pm(t, 1)} | "
                f"{t['rhat']:.3f}, {t['ess']:.0f} | {_pm(w, 3)} | "
                + ", ".join(f"{x:.2f}" for x in (w or {}).get("replica_means") or [])
                + f" | {'-' if acc is None else f'{acc:.2f}'} | "
                + ("converged" if row["converged"] else "NOT CONVERGED: " + row["reason"])
                + " |")
        lines.append("")
    return "\n".join(lines)


def maxwell_table(results: list[dict]) -> str:
    """The Maxwell relation dGamma/dF = -(1/2 pi) dz/dn (Mosconi et al. 2009, Eq. 2) where
    runs at three or more evenly spaced catenations share their forces: at each inner
    catenation and inner force, dGamma/dF by the three-point derivative over the rungs
    (uneven spacing) and dz/dn by the central difference over the catenations. Errors add
    in quadrature as if independent; neighbouring rungs of one ladder are positively
    correlated through the swaps, which makes the true error of a difference smaller, so
    |z| is, if anything, understated."""
    by = {}
    for r in results:
        by.setdefault((r["length_nm"], r["salt_mM"], tuple(r["forces_pN"])), {})[r["turns"]] = r
    lines = []
    for (L, salt, forces), runs in by.items():
        ns = sorted(runs)
        if len(ns) < 3 or len(forces) < 3:
            continue
        lines += [f"### Maxwell relation, 2 x {L:g} nm, {salt:g} mM", "",
                  "| n | F (pN) | dGamma/dF (nm) | -(1/2 pi) dz/dn (nm) | z |",
                  "|---|---|---|---|---|"]
        for i in range(1, len(ns) - 1):
            n0, n1, n2 = ns[i - 1], ns[i], ns[i + 1]
            for k in range(1, len(forces) - 1):
                f0, f1, f2 = forces[k - 1], forces[k], forces[k + 1]
                g = [runs[n1]["rows"][j]["torque_pN_nm"] for j in (k - 1, k, k + 1)]
                # three-point derivative at f1 on an uneven grid
                h1, h2 = f1 - f0, f2 - f1
                c = (-h2 / (h1 * (h1 + h2)), (h2 - h1) / (h1 * h2), h1 / (h2 * (h1 + h2)))
                dg = sum(ci * gi["mean"] for ci, gi in zip(c, g))
                edg = math.sqrt(sum((ci * gi["sem"]) ** 2 for ci, gi in zip(c, g)))
                za, zb = (runs[m]["rows"][k]["extension_nm"] for m in (n0, n2))
                dz = -(zb["mean"] - za["mean"]) / (n2 - n0) / (2 * math.pi)
                edz = math.hypot(za["sem"], zb["sem"]) / (n2 - n0) / (2 * math.pi)
                zsc = (dg - dz) / math.hypot(edg, edz)
                lines.append(f"| {n1:g} | {f1:g} | {dg:.2f} +- {edg:.2f} | "
                             f"{dz:.2f} +- {edz:.2f} | {zsc:+.2f} |")
        lines.append("")
    return "\n".join(lines)


def cmd_report(a) -> None:
    results = [json.loads(p.read_text())
               for p in sorted(RESULTS.glob("braid_force_ladder_*.json"))]
    results.sort(key=lambda r: r["turns"])
    text = render(results) + "\n" + maxwell_table(results)
    if a.reading:
        text += "\n" + pathlib.Path(a.reading).read_text()
    (RESULTS / "braid_force_ladder.md").write_text(text + "\n")
    plot(results, RESULTS / "braid_force_ladder.png")
    print(text)


def plot(results, path) -> None:
    """Extension against force per catenation (open marks: NOT CONVERGED) and the axis
    writhe of each ladder (dots) with the mean across ladders."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 4))
    for i, res in enumerate(results):
        c = f"C{i}"
        rows = res["rows"]
        F = np.array([r["force_pN"] for r in rows])
        z = np.array([r["extension_nm"]["mean"] for r in rows])
        ez = np.array([r["extension_nm"]["sem"] for r in rows])
        ok = np.array([r["converged"] for r in rows])
        lab = f"n = {res['turns']:g}"
        ax1.errorbar(F, z, yerr=ez, color=c, ls="-", lw=1, capsize=2, label=lab)
        ax1.plot(F[ok], z[ok], "o", color=c)
        ax1.plot(F[~ok], z[~ok], "o", mfc="white", color=c)
        w = np.array([r["wr_axis"]["mean"] for r in rows])
        ax2.plot(F, w, "-", color=c, label=lab)
        for f, r in zip(F, rows):
            m = r["wr_axis"].get("replica_means") or []
            ax2.plot([f] * len(m), m, ".", color=c, alpha=0.6)
    ax1.set_xlabel("force (pN)")
    ax1.set_ylabel("extension (nm)")
    ax1.set_title("open: NOT CONVERGED")
    ax1.legend()
    ax2.set_xlabel("force (pN)")
    ax2.set_ylabel("braid-axis writhe Wr_ax (turns)")
    ax2.set_title("dots: one ladder each")
    fig.suptitle(f"2 x {results[0]['length_nm']:g} nm braid, force ladders")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run", help="run R force ladders at one catenation")
    r.add_argument("--length", type=float, default=100.0, help="nm per strand")
    r.add_argument("--turns", type=float, default=2.5, help="catenation (trap turns)")
    r.add_argument("--forces", type=float, nargs="+",
                   default=[0.5, 0.8, 1.25, 2.0, 3.0], help="rungs, pN, increasing")
    r.add_argument("--salt", type=float, default=150.0, help="mM")
    r.add_argument("--separation", type=float, default=40.0, help="tether separation, nm")
    r.add_argument("--replicas", type=int, default=4, help="independent ladders")
    r.add_argument("--rounds", type=int, default=6000)
    r.add_argument("--eq-rounds", type=int, default=300)
    r.add_argument("--round-moves", type=int, default=2000)
    r.add_argument("--rung-moves", type=int, default=200_000,
                   help="moves per rung from its built start before the swaps begin")
    r.add_argument("--frame-every", type=int, default=10, help="rounds between writhe frames")
    r.add_argument("--seed", type=int, default=1)
    r.add_argument("--workers", type=int, default=2)
    r.add_argument("--work", default="runs/braid_force_ladder")
    p = sub.add_parser("report", help="tables from the stored runs")
    p.add_argument("--reading", default=None, help="a file appended to the md")
    a = ap.parse_args(argv)
    if a.cmd == "run":
        if any(y <= x for x, y in zip(a.forces, a.forces[1:])):
            ap.error("--forces must increase")
        if a.rounds < 2 * a.frame_every:
            ap.error("--rounds must be >= 2 x --frame-every")
        cmd_run(a)
    else:
        cmd_report(a)


if __name__ == "__main__":
    main()
