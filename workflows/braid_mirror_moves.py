"""Are the braid's Metropolis moves handedness-neutral?  Moves alone (no Brownian dynamics)
at turns +n and at the y -> -y mirror image (-n, trap angle negated).

Three checks, written as one table to workflows/results/braid_mirror_moves.md:

A. The model: energy (every term) and catenation of a start and of its mirror (E equal,
   catenation negated); the start builder at -n against the mirror of its start at +n
   (exact with ``start_spread`` = 0; with overdispersed starts the braid-axis bow keeps its
   direction psi, drawn from the seed alone, so +n and -n starts of one seed are not
   mirrors, only mirror-distributed).
B. Mirror coupling (sample-path test of the kernel, ``BraidMoves.run_with``): the chain at
   +n and the chain from the mirrored start at -n are fed the *mirrored* random numbers
   (per kind: the rotation angles' uniforms u -> 1 - u for crankshaft, twist, sway, pivot
   and tilt, the shear's and the sway's azimuth u -> 1 - u, the bead move's Gaussian y
   negated; kind choice, strand choice, positions in the strand, radii, stretch, breathe
   and the acceptance uniform kept). If every proposal and acceptance is mirror-covariant
   the -n chain is the exact mirror of the +n chain move by move (to round-off): then no
   move kind can bias z(+n) - z(-n) in law, whatever its detailed balance. The -n chain is
   re-set to the exact mirror after every block (round-off does not accumulate); a block
   whose positions differ by more than 1e-6 nm, or whose per-kind accepted/refused counts
   differ, is a handedness-dependent decision.
C. Independent chains (different seeds) at +n and -n from mirrored starts: mean extension
   (attachments' mean height, the scene's extension_nm) with batch-means errors
   (Flyvbjerg-Petersen blocking, dnabraid.analysis.stats.blocking_sem), and the per-kind
   acceptances.

Usage: python workflows/braid_mirror_moves.py [--length 100] [--turns 1] [--blocks 2000]
       [--chain-moves 2e7 (0: A and B only)] [--sample 500] [--seed 1] [--append]
(run it pinned to one core: taskset -c 1, NUMBA_NUM_THREADS=1)
"""

from __future__ import annotations

import argparse
import datetime
import pathlib
import time

import numpy as np

from dnabraid.analysis.stats import blocking_sem
from dnabraid.kernels.braid_moves import BRAID_KINDS, catenation
from dnabraid.run.chain_moves import BraidMoves, mirror_random
from dnabraid.scenes import make_scene

HERE = pathlib.Path(__file__).resolve().parent
MIRROR = np.array([1.0, -1.0, 1.0])
#: the scene's move amplitudes (dnabraid.scenes.braid defaults)
AMPS = dict(crank_angle_rad=2.0, bead_move_nm=0.3, shear_nm=3.0, shear_z_nm=1.0,
            twist_rad=0.05, sway_rad=0.1, pivot_rad=0.15, tilt_rad=0.1, stretch_eps=0.01,
            breathe_eps=0.1, breathe_max_beads=40, crank_max_beads=40)
#: per kind, the columns of ``uni`` whose uniform is mirrored u -> 1 - u (an angle's sign
#: or an azimuth); the bead kind (1) mirrors its Gaussian's y instead


def build(length_nm: float, turns: float, seed: int = 1, **kw):
    # trap pinned: the braid's default is K = 2000 since 2026-12-06; the stored table was
    # measured in the stiff trap of the time
    sc = make_scene("braid", dict({"length_nm": length_nm, "force_pN": 2.0, "turns": [turns],
                                   "replicas": 1, "seed": seed,
                                   "trap_stiffness_pN_nm": 20000.0}, **kw))
    return sc, sc.build()


def moves(model, turns: float, seed: int) -> BraidMoves:
    mv = BraidMoves.for_model(model, moves_per_call=1000, seed=seed, guard_every=0, **AMPS)
    mv.energy.set_trap_angle(2 * np.pi * turns)
    return mv


def run_with(mv: BraidMoves, pos, uni, gau) -> float:
    """The moves on ``pos`` (in place) with the given random numbers; the catenation."""
    return float(mv.run_with(pos, uni, gau)[2])


def check_model(length_nm: float, turns: float) -> dict:
    sc, m = build(length_nm, turns)
    sc0, _ = build(length_nm, turns, start_spread=0.0)
    p = np.array(sc.start_positions(m, turns), float)
    e_p = moves(m, turns, 1).energy.total_terms(p)
    e_m = moves(m, -turns, 1).energy.total_terms(p * MIRROR)
    return {"dE_max": max(abs(e_p[t] - e_m[t]) for t in e_p),
            "cat_sum": catenation(p, *m.chains) + catenation(p * MIRROR, *m.chains),
            "start0": float(np.abs(np.asarray(sc0.start_positions(m, -turns))
                                   - np.asarray(sc0.start_positions(m, turns)) * MIRROR).max()),
            "start1": float(np.abs(np.asarray(sc.start_positions(m, -turns))
                                   - p * MIRROR).max())}


def coupled(length_nm: float, turns: float, blocks: int, per_block: int = 1000,
            seed: int = 1, burn_blocks: int = 20) -> dict:
    """Check B: mirror-coupled chains, re-synchronised after every block."""
    sc, m = build(length_nm, turns, seed=seed)
    pp = np.array(sc.start_positions(m, turns), float)
    mp, mm = moves(m, turns, seed), moves(m, -turns, seed)
    rng = np.random.default_rng([seed, 0xC0])
    for _ in range(burn_blocks):  # leave the built start
        run_with(mp, pp, rng.random((per_block, 6)), rng.standard_normal((per_block, 3)))
    mp._stats[:] = 0
    mm.stretch_ratio = mp.stretch_ratio  # fixed at a moves object's first call: share it
    worst, bad, cat_dev = 0.0, 0, 0.0
    t0 = time.process_time()
    for _ in range(blocks):
        pm = pp * MIRROR
        uni, gau = rng.random((per_block, 6)), rng.standard_normal((per_block, 3))
        u2, g2 = mirror_random(mp._cum, uni, gau)
        sp, sm = mp._stats.copy(), mm._stats.copy()
        cp = run_with(mp, pp, uni, gau)
        cm = run_with(mm, pm, u2, g2)
        dev = float(np.abs(pm - pp * MIRROR).max())
        same = np.array_equal(mp._stats - sp, mm._stats - sm)
        worst = max(worst, dev)
        cat_dev = max(cat_dev, abs(cp + cm))
        bad += int(dev > 1e-6 or not same)
    return {"turns": turns, "moves": blocks * per_block, "worst_dev_nm": worst,
            "bad_blocks": bad, "blocks": blocks, "cat_dev": cat_dev,
            "accepted": mp._stats[:, 2].copy(), "attempted": mp._stats[:, 0].copy(),
            "refused": mp._stats[:, 1].copy(), "cpu_s": time.process_time() - t0}


def chain(length_nm: float, turns: float, sign: int, n_moves: int, sample: int, seed: int,
          burn: int) -> dict:
    """Check C: one chain at sign x turns from the (mirrored, for sign -1) start of +turns."""
    sc, m = build(length_nm, turns, seed=1)
    pos = np.array(sc.start_positions(m, turns), float)
    if sign < 0:
        pos = pos * MIRROR
    mv = moves(m, sign * turns, seed)
    mv.moves_per_call = sample
    att = list(m.attachments)
    t0 = time.process_time()
    for _ in range(burn // sample):
        pos, _ = mv.run(pos)
    mv._stats[:] = 0
    z = np.empty(n_moves // sample)
    for i in range(len(z)):
        pos, _ = mv.run(pos)
        z[i] = pos[att, 2].mean()
    b = blocking_sem(z)
    x = z - z.mean()
    return {"mean": b["mean"], "sem": b["sem"], "sd": float(z.std()), "converged": b["converged"],
            "tau_samples": float((b["sem"] / (z.std() / np.sqrt(len(z)))) ** 2),
            "cat": mv.catenation, "stats": mv._stats.copy(), "n": len(z),
            "cpu_s": time.process_time() - t0}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--length", type=float, default=100.0)
    ap.add_argument("--turns", type=float, nargs="+", default=[1.0, 1.25])
    ap.add_argument("--blocks", type=int, default=2000, help="coupled blocks of 1000 moves")
    ap.add_argument("--chain-moves", type=float, default=2e7)
    ap.add_argument("--burn", type=float, default=1e6)
    ap.add_argument("--sample", type=int, default=500)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--append", action="store_true", help="append to the table")
    ap.add_argument("--table", default=str(HERE / "results" / "braid_mirror_moves.md"))
    a = ap.parse_args(argv)
    L, n0 = a.length, a.turns[0]
    lines = [f"# Braid moves alone at +n and at its mirror -n ({datetime.datetime.now():%Y-%m-%d %H:%M})",
             "",
             f"`python workflows/braid_mirror_moves.py --length {L:g} --turns "
             f"{' '.join(f'{t:g}' for t in a.turns)} --blocks {a.blocks} --chain-moves "
             f"{a.chain_moves:g} --burn {a.burn:g} --sample {a.sample} --seed {a.seed}`: "
             f"braid 2 x {L:g} nm, 2 pN, tethers 40 nm, the scene's move amplitudes and "
             "weights (nine kinds), no dynamics; one core.", ""]
    print("A: model", flush=True)
    lines += ["## A. The model and the start builder", "",
              "| turns | max |E_k(x, +n) - E_k(Mx, -n)| pN nm | cat(x) + cat(Mx) | start(-n) vs "
              "M start(+n), start_spread 0 (nm) | same, start_spread 1 (nm) |", "|---|---|---|---|---|"]
    for t in a.turns:
        r = check_model(L, t)
        lines.append(f"| {t:g} | {r['dE_max']:.2e} | {r['cat_sum']:.1e} | {r['start0']:.1e} | "
                     f"{r['start1']:.1f} |")
    lines += ["", "## B. Mirror-coupled chains (mirrored random numbers, re-synchronised every "
              "1000 moves)", "",
              "| turns | moves | blocks with a handedness-dependent decision | largest "
              "block deviation nm | largest |cat(+) + cat(-)| | accepted per kind "
              f"({', '.join(BRAID_KINDS)}) | refused (topology) | CPU s |",
              "|---|---|---|---|---|---|---|---|"]
    for t in a.turns:
        print("B: coupled", t, flush=True)
        r = coupled(L, t, a.blocks, seed=a.seed)
        lines.append(f"| {t:g} | {r['moves']:.1e} | {r['bad_blocks']} of {r['blocks']} | "
                     f"{r['worst_dev_nm']:.1e} | {r['cat_dev']:.1e} | "
                     f"{', '.join(str(int(x)) for x in r['accepted'])} | "
                     f"{int(r['refused'][0])} crank, {int(r['refused'][1:8].sum())} bead..stretch "
                     f"(+{int(r['refused'][8])} breathe, geometric or topology) | "
                     f"{r['cpu_s']:.0f} |")
    if a.chain_moves <= 0:
        return _write(a, lines)
    print("C: chains", n0, flush=True)
    res = {}
    for sign, seed in ((+1, 100 + a.seed), (-1, 200 + a.seed)):
        res[sign] = chain(L, n0, sign, int(a.chain_moves), a.sample, seed, int(a.burn))
        print(sign, res[sign]["mean"], res[sign]["sem"], res[sign]["cpu_s"], flush=True)
    d = res[1]["mean"] - res[-1]["mean"]
    se = float(np.hypot(res[1]["sem"], res[-1]["sem"]))
    lines += ["", f"## C. Independent chains at n = +{n0:g} and -{n0:g} (mirrored starts; "
              f"seeds {100 + a.seed}, {200 + a.seed}; {a.burn:.0e} moves discarded, then "
              f"{a.chain_moves:.0e} moves sampled every {a.sample})", "",
              "| turns | extension nm | blocking SE nm | sd nm | tau (samples) | blocking "
              "plateau | final catenation | acceptance per kind | CPU s |",
              "|---|---|---|---|---|---|---|---|---|"]
    for sign in (1, -1):
        r = res[sign]
        st = r["stats"]
        acc = ", ".join(f"{st[k, 2] / max(st[k, 0], 1):.4f}" for k in range(len(BRAID_KINDS)))
        lines.append(f"| {sign * n0:+g} | {r['mean']:.3f} | {r['sem']:.3f} | {r['sd']:.2f} | "
                     f"{r['tau_samples']:.0f} | {'yes' if r['converged'] else 'NO'} | "
                     f"{r['cat']:+.3f} | {acc} | {r['cpu_s']:.0f} |")
    lines += ["", f"z(+{n0:g}) - z(-{n0:g}) = **{d:+.3f} +- {se:.3f} nm** ({d / se:+.1f} SE).",
              ""]
    return _write(a, lines)


def _write(a, lines) -> int:
    out = pathlib.Path(a.table)
    out.parent.mkdir(parents=True, exist_ok=True)
    with open(out, "a" if a.append else "w") as fh:
        fh.write("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
