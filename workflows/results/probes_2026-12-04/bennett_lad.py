import sys, math, json, numpy as np, warnings
warnings.filterwarnings("ignore")
sys.path.insert(0, '/work/main/workflows')
import MDAnalysis as mda
import plectoneme_mc_reference as ref
from dnabraid.run.ladder import swap_map
run = sys.argv[1]; ni, nj = float(sys.argv[2]), float(sys.argv[3]); ti, tj = sys.argv[4], sys.argv[5]
R = int(sys.argv[6])
def frames(r, tag):
    u = mda.Universe(f'{run}/topology.pdb', f'{run}/replicas/r{r:02d}/points/{tag}/trajectory.dcd')
    return [ts.positions.astype(float) / 10.0 for ts in u.trajectory]
s, m, mv = ref.moves_chain(ni, 300.0, 1.0, 1)
c, sides, mo = np.asarray(m.chains[0]), np.asarray(m.sides), int(m.bead_orientation)
d = 2 * math.pi * (nj - ni); kT = m.dna.kT
X = [frames(r, ti) for r in range(R)]; Y = [frames(r, tj) for r in range(R)]
rows = []
for r in range(R):
    xs, ys = X[r], Y[(r + 1) % R]
    n = min(len(xs), len(ys))
    for k in range(n):
        a, b = xs[k], ys[k]
        mv.energy.set_trap_angle(2 * math.pi * ni); ui = mv.energy.total(a)
        ui2 = mv.energy.total(swap_map(b, c, sides, mo, -d))
        mv.energy.set_trap_angle(2 * math.pi * nj); uj = mv.energy.total(b)
        uj2 = mv.energy.total(swap_map(a, c, sides, mo, d))
        de = (uj2 - ui + ui2 - uj) / kT
        rows.append((r, min(1.0, math.exp(-de)), b[c[-1], 2] - b[c[0], 2], a[c[-1], 2] - a[c[0], 2], de))
r = np.array(rows)
ex = np.exp(-r[:, 4]); dr = r[:, 1] * (r[:, 2] - r[:, 3])
# SE from the spread over ladder pairs (independent)
per = np.array([[ex[r[:, 0] == q].mean(), dr[r[:, 0] == q].mean()] for q in range(R)])
out = {"pairs": len(r), "acc": r[:, 1].mean(), "bennett": ex.mean(), "bennett_sem": per[:, 0].std(ddof=1) / math.sqrt(R),
       "drift": dr.mean(), "drift_sem": per[:, 1].std(ddof=1) / math.sqrt(R), "per_ladder": per.tolist()}
print(json.dumps(out, indent=1))
