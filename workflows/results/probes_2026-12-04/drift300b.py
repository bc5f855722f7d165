"""Bennett / stationarity identities of the mapped swap on independent moves-only samples at
300 nm, 1 pN, rungs n_i = 3, n_j = 3 + 1/6: E[exp(-Delta)] = 1 and E[a (z_j - z_i)] = 0
if both sample sets are Boltzmann (the swap is exact)."""
import sys, math, json, time, multiprocessing as mp
import numpy as np
sys.path.insert(0, '/work/main/workflows')
L, F = 300.0, 1.0
N_I, N_J = 3.0, 3.0 + 1 / 6
BUD = float(sys.argv[1]); EVERY = 5000

def chain(args):
    n, seed = args
    import plectoneme_mc_reference as ref
    s, m, mv = ref.moves_chain(n, L, F, seed)
    pos = ref.ramp(mv, np.array(m.positions), 2 * math.pi * n)
    pos, _ = mv.run(pos, 1_000_000)
    out = []
    t0 = time.process_time()
    while time.process_time() - t0 < BUD:
        pos, _ = mv.run(pos, EVERY); out.append(pos.copy())
    return np.array(out)

def block_sem(x, nb=20):
    n = len(x) // nb * nb
    b = x[:n].reshape(nb, -1).mean(1)
    return b.std(ddof=1) / math.sqrt(nb)

if __name__ == '__main__':
    with mp.get_context('spawn').Pool(2) as pool:
        xi, xj = pool.map(chain, [(N_I, 33), (N_J, 34)])
    np.savez('/tmp/s13/drift300b_samples.npz', xi=xi, xj=xj)
    import plectoneme_mc_reference as ref
    from dnabraid.run.ladder import swap_map
    s, m, mv = ref.moves_chain(N_I, L, F, 31)
    c, sides, mo = np.asarray(m.chains[0]), np.asarray(m.sides), int(m.bead_orientation)
    d = 2 * math.pi * (N_J - N_I); kT = m.dna.kT
    n = min(len(xi), len(xj)); rows = []
    for shift in (0, n // 3, 2 * n // 3):
        for k in range(n):
            a, b = xi[k], xj[(k + shift) % n]
            mv.energy.set_trap_angle(2 * math.pi * N_I); ui = mv.energy.total(a)
            ui2 = mv.energy.total(swap_map(b, c, sides, mo, -d))
            mv.energy.set_trap_angle(2 * math.pi * N_J); uj = mv.energy.total(b)
            uj2 = mv.energy.total(swap_map(a, c, sides, mo, d))
            de = (uj2 - ui + ui2 - uj) / kT
            rows.append((min(1.0, math.exp(-de)), b[c[-1], 2] - b[c[0], 2],
                         a[c[-1], 2] - a[c[0], 2], de))
    r = np.array(rows)
    dr = r[:, 0] * (r[:, 1] - r[:, 2])
    ex = np.exp(-r[:, 3])
    out = {"pairs": len(r), "samples": [len(xi), len(xj)], "acc": r[:, 0].mean(),
           "z_i": r[:n, 2].mean(), "z_i_sem": block_sem(r[:n, 2]),
           "z_j": r[:n, 1].mean(), "z_j_sem": block_sem(r[:n, 1]),
           "drift": dr.mean(), "drift_sem": block_sem(dr[:n]) / math.sqrt(3) * math.sqrt(2),
           "bennett": ex.mean(), "bennett_sem": block_sem(ex[:n]) / math.sqrt(3) * math.sqrt(2)}
    print(json.dumps(out, indent=1))
    json.dump(out, open('/tmp/s13/drift300b.json', 'w'), indent=1)
