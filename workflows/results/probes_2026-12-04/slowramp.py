"""Moves-only chains at 300 nm, 1 pN, n = 3 after a ramp 10x slower than the reference's
(400 stages x 20000 moves = 8e6 moves, then 1e6): does the ramp speed move <z>?"""
import sys, math, json, time, multiprocessing as mp
import numpy as np
sys.path.insert(0, '/work/main/workflows')
BUD = float(sys.argv[1]); RAMP = int(sys.argv[2]); SEEDS = [int(x) for x in sys.argv[3:]]

def run(seed):
    import plectoneme_mc_reference as ref
    ref.RAMP_MOVES = RAMP
    s, m, mv = ref.moves_chain(3.0, 300.0, 1.0, seed)
    pos = ref.ramp(mv, np.array(m.positions), 2 * math.pi * 3.0)
    c = np.asarray(m.chains[0]); z = []
    t0 = time.process_time()
    while time.process_time() - t0 < BUD:
        pos, _ = mv.run(pos, 500); z.append(pos[c[-1], 2] - pos[c[0], 2])
    z = np.array(z); q = len(z) // 4
    return seed, float(z.mean()), [float(z[i*q:(i+1)*q].mean()) for i in range(4)], len(z)

if __name__ == '__main__':
    with mp.get_context('spawn').Pool(2) as pool:
        res = pool.map(run, SEEDS)
    for r in res: print(r)
    M = np.array([r[1] for r in res])
    print('ramp moves/stage', RAMP, 'mean %.2f +- %.2f' % (M.mean(), M.std(ddof=1) / math.sqrt(len(M))))
    json.dump({"ramp_moves_per_stage": RAMP, "chains": res}, open(f'/tmp/s13/slowramp_{RAMP}.json', 'w'))
