"""Moves alone from ladder states at n = 3 whose plectoneme sits at an end or in the middle:
how fast does the plectoneme's position (and z) forget where it started?"""
import sys, math, json, time, glob, multiprocessing as mp, warnings
import numpy as np, pandas as pd
warnings.filterwarnings("ignore")
sys.path.insert(0, '/work/main/workflows')
EVERY, TOTAL = 20000, 12_000_000

def pick():
    import MDAnalysis as mda
    out = []
    for r in range(8):
        d = f'/tmp/s13/lad3/replicas/r{r:02d}/points/000_turns+003.0000'
        fr = pd.read_csv(f'{d}/frames.csv')
        u = mda.Universe('/tmp/s13/lad3/topology.pdb', f'{d}/trajectory.dcd')
        tips = fr.plectoneme_tip_nm.values; cnt = fr.plectonemes.values
        want = 'end' if r % 2 == 0 else 'mid'
        ok = [(k, t) for k, (t, c) in enumerate(zip(tips, cnt)) if c >= 1 and
              ((t < 60 or t > 240) if want == 'end' else (130 < t < 170))]
        k, t = ok[-1]
        u.trajectory[k]
        out.append((want, r, float(t), u.atoms.positions.astype(float) / 10.0))
    return out

def run(args):
    want, r, t0, pos = args
    import plectoneme_mc_reference as ref
    from dnabraid.observables import plectoneme_summary
    s, m, mv = ref.moves_chain(3.0, 300.0, 1.0, 50 + r)
    mv.energy.set_trap_angle(2 * math.pi * 3.0)
    c = np.asarray(m.chains[0])
    rows = []
    for i in range(TOTAL // EVERY):
        pos, _ = mv.run(pos, EVERY)
        pl = plectoneme_summary(pos[c])
        rows.append((pos[c[-1], 2] - pos[c[0], 2], pl['count'], pl['tip_nm']))
    return want, r, t0, rows

if __name__ == '__main__':
    jobs = pick()
    with mp.get_context('spawn').Pool(2) as pool:
        res = pool.map(run, jobs)
    json.dump([(w, r, t0, rows) for w, r, t0, rows in res], open('/tmp/s13/tipcont.json', 'w'))
    for w, r, t0, rows in res:
        a = np.array(rows, float)
        q = len(a) // 4
        print(w, r, 'tip0 %.0f' % t0, 'tip by quarter', [round(float(np.nanmean(a[i*q:(i+1)*q, 2])), 0) for i in range(4)],
              'z by quarter', [round(float(a[i*q:(i+1)*q, 0].mean()), 1) for i in range(4)],
              'first tips', [round(x) if x == x else None for x in a[:8, 2]])
