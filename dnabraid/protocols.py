"""Protocols: the magnetic-tweezer turn schedule (step n, equilibrate, sample), resumable.

The turn values are run as two branches that start from the value nearest zero: upwards
through the positive values, then, starting again from the state saved after the first
value, downwards through the negative ones, so no turn is ramped twice. Each finished
value is checkpointed (observables, frames and the final state) before the next one
starts; a rerun into the same directory loads finished values instead of running them.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import os

import numpy as np

from .analysis.geometry import catenation_number
from .analysis.twist import plectoneme_summary, tether_twist, writhe_open
from .build import Model
from .engine import Engine

log = logging.getLogger(__name__)

TWO_PI = 2.0 * math.pi


@dataclasses.dataclass
class PointResult:
    """Samples at one turn value.

    Attributes
    ----------
    turns : float
    step : ndarray (n,) step index of each observable sample
    extension_nm, torque_pN_nm, bead_angle_turns : ndarray (n,)
    frame_step : ndarray (m,)
    catenation : ndarray (m,)  (nan for a single tether)
    frames : ndarray (m, N, 3) positions in nm

    Twisted scenes (plectoneme) also carry (None otherwise):

    twist_torque_pN_nm : ndarray (n,)
        Torque from the twist, 2 pi Tw C kT / L: the mean of g_j omega_j over the joints
        weighted by 1/g_j; each joint's <g_j omega_j> equals the torque on the bead exactly
        (rotate the frames beyond joint j), and this average is far less noisy than the
        trap's -K sin(lag).
    twist, writhe : ndarray (m,)
        Tw (clamps included) and Wr (vertical-ray closure) per frame, turns.
    plectonemes, plectoneme_length_nm, plectoneme_tip_nm : ndarray (m,)
        Number of plectonemes, DNA in them and the tip (contour position from the
        surface) of the longest, per frame (:func:`dnabraid.analysis.twist.find_plectonemes`).
    """

    turns: float
    step: np.ndarray
    extension_nm: np.ndarray
    torque_pN_nm: np.ndarray
    bead_angle_turns: np.ndarray
    frame_step: np.ndarray
    catenation: np.ndarray
    frames: np.ndarray
    twist_torque_pN_nm: np.ndarray | None = None
    twist: np.ndarray | None = None
    writhe: np.ndarray | None = None
    plectonemes: np.ndarray | None = None
    plectoneme_length_nm: np.ndarray | None = None
    plectoneme_tip_nm: np.ndarray | None = None

    def save(self, path: str) -> None:
        tmp = path + ".tmp.npz"
        np.savez_compressed(tmp, **{f.name: getattr(self, f.name)
                                    for f in dataclasses.fields(self)
                                    if getattr(self, f.name) is not None})
        os.replace(tmp, path)

    @classmethod
    def load(cls, path: str) -> PointResult:
        with np.load(path) as z:
            kw = {f.name: z[f.name] for f in dataclasses.fields(cls) if f.name in z.files}
        kw["turns"] = float(kw["turns"])
        return cls(**kw)


def branches(turns) -> list[list[float]]:
    """Split turn values into an upward branch from the value nearest 0 and a downward one."""
    ts = sorted(float(t) for t in turns)
    start = min(ts, key=lambda t: (abs(t), t))
    up = [t for t in ts if t >= start]
    down = [t for t in reversed(ts) if t < start]
    return [up, down]


def _tag(t: float) -> str:
    return f"{t:+09.4f}"


def steps_for(model: Model, current: float, target: float) -> int:
    s = model.scene
    ramp = 0 if not s.turned else int(math.ceil(abs(target - current) / s.turn_rate))
    ramp = int(math.ceil(ramp / s.report_interval)) * s.report_interval
    return ramp + s.equilibration_steps + s.steps


def total_steps(model: Model) -> int:
    tot = 0
    for k, br in enumerate(branches(model.scene.turns)):
        cur = 0.0 if k == 0 else branches(model.scene.turns)[0][0]
        for t in br:
            tot += steps_for(model, cur, t)
            cur = t
    return tot


class TweezerProtocol:
    """Run a tweezer scene's turn schedule on an :class:`Engine`, with checkpoints.

    Parameters
    ----------
    model : Model
    engine : Engine
    checkpoint_dir : str
        Where finished values and states are kept (created if needed).
    progress : callable(int), optional
        Called with the number of steps just taken.
    """

    def __init__(self, model: Model, engine: Engine, checkpoint_dir: str, progress=None):
        self.model = model
        self.engine = engine
        self.dir = checkpoint_dir
        self.progress = progress or (lambda n: None)
        os.makedirs(self.dir, exist_ok=True)
        self.braid = model.scene.n_strands == 2
        self.turned = model.scene.turned
        self.twisted = model.scene.twisted
        self.K = model.scene.trap_stiffness_pN_nm
        if self.twisted:
            s = model.scene
            # torque = 2 pi Tw / (twist compliance L / (C kT)), L the rest contour length
            self._tw_torque = (2.0 * math.pi * s.twist_persistence_nm * model.params["kT_pN_nm"]
                               / (s.length_nm))

    def _paths(self, t):
        return (os.path.join(self.dir, f"point_{_tag(t)}.npz"),
                os.path.join(self.dir, f"state_{_tag(t)}.xml"))

    def run(self) -> list[PointResult]:
        """Run (or load) every turn value; return results sorted by turns."""
        s = self.model.scene
        results = {}
        init_state = os.path.join(self.dir, "state_initial.xml")
        if os.path.exists(init_state):
            self.engine.load_state(init_state)
        else:
            self.engine.minimise()
            self.engine.save_state(init_state)
        self._sync_angle(0.0)
        brs = branches(s.turns)
        for k, br in enumerate(brs):
            if not br:
                continue
            if k == 0:
                cur = 0.0
            else:
                cur = brs[0][0]
                self.engine.load_state(self._paths(cur)[1])
                self._sync_angle(cur)
            for t in br:
                pfile, sfile = self._paths(t)
                if os.path.exists(pfile) and os.path.exists(sfile):
                    results[t] = PointResult.load(pfile)
                    self.engine.load_state(sfile)
                    self._sync_angle(t)
                    self.progress(steps_for(self.model, cur, t))
                    log.info("turns=%g loaded from checkpoint", t)
                else:
                    results[t] = self._run_point(cur, t)
                    results[t].save(pfile)
                    self.engine.save_state(sfile)
                cur = t
        return [results[t] for t in sorted(results)]

    # ------------------------------------------------------------------------
    def _sync_angle(self, turns: float) -> None:
        """Unwrap the bead angle of the current state next to the trap angle 2 pi turns."""
        self._phi = TWO_PI * turns
        if self.turned:
            self._bead_angle(self.engine.positions())

    def _bead_angle(self, pos) -> float:
        """Bead angle (rad), unwrapped continuously from the previous sample."""
        att = self.model.attachments
        if self.twisted:
            u = pos[self.model.bead_orientation] - pos[att[0]]
        else:
            u = pos[att[1]] - pos[att[0]]
        raw = math.atan2(u[1], u[0])
        self._phi = self._phi + ((raw - self._phi + math.pi) % TWO_PI - math.pi)
        return self._phi

    def _observe(self, pos, angle0):
        m = self.model
        ext = float(np.mean(pos[m.attachments, 2]))
        if not self.turned:
            return ext, math.nan, math.nan
        phi = self._bead_angle(pos)
        lag = phi - angle0
        if abs(lag) > 0.5 * math.pi:
            self.engine.blow_up(
                f"the bead slipped in the rotational trap (bead {phi / TWO_PI:.3f} turns, trap "
                f"{angle0 / TWO_PI:.3f} turns): the braid's torque exceeded the trap stiffness "
                f"K = {self.K} pN nm or the turns were ramped too fast (turn_rate = "
                f"{self.model.scene.turn_rate}); raise trap_stiffness_pN_nm or lower turn_rate")
        torque = -self.K * math.sin(lag)  # torque the trap applies to hold the braid
        return ext, torque, phi / TWO_PI

    def _twist(self, pos) -> float:
        m = self.model
        c = m.chains[0]
        return tether_twist(pos[c], pos[m.sides], pos[m.bead_orientation] - pos[c[-1]])

    def _catenation(self, pos):
        if not self.braid:
            return math.nan
        c = self.model.chains
        return catenation_number(pos[c[0]], pos[c[1]])

    def _run_point(self, current: float, target: float) -> PointResult:
        s = self.model.scene
        e = self.engine
        ri = s.report_interval
        fail_dir = os.path.dirname(self.dir)
        # 1. ramp the trap angle
        if self.turned:
            nramp = int(math.ceil(abs(target - current) / s.turn_rate / ri))
            for i in range(1, nramp + 1):
                ang = TWO_PI * (current + (target - current) * i / nramp)
                e.set_parameter("trap_angle", ang)
                pos = e.advance(ri, fail_dir)
                self._observe(pos, ang)
                self.progress(ri)
            e.set_parameter("trap_angle", TWO_PI * target)
        angle0 = TWO_PI * target
        # 2. equilibrate
        left = s.equilibration_steps
        while left > 0:
            n = min(left, ri)
            pos = e.advance(n, fail_dir)
            self._observe(pos, angle0)
            self.progress(n)
            left -= n
        # 3. sample
        nsamp = s.steps // ri
        every = s.frame_interval // ri
        step, ext, tor, ang, twt = (np.empty(nsamp) for _ in range(5))
        fsteps, cats, frames = [], [], []
        tws, wrs, npl, lpl, tpl = [], [], [], [], []
        for i in range(nsamp):
            pos = e.advance(ri, fail_dir)
            self.progress(ri)
            step[i] = e.step
            ext[i], tor[i], ang[i] = self._observe(pos, angle0)
            if self.twisted:
                twt[i] = self._tw_torque * self._twist(pos)
            if (i + 1) % every == 0:
                if self.twisted:
                    c = self.model.chains[0]
                    tw, wr = self._twist(pos), writhe_open(pos[c])
                    if abs(tw + wr - ang[i]) > 0.5:
                        e.blow_up(f"Tw + Wr = {tw + wr:.3f} no longer equals the bead angle "
                                  f"{ang[i]:.3f} turns: the DNA passed through itself (or a "
                                  "closing ray) and changed its linking number", None, None)
                    pl = plectoneme_summary(pos[c])
                    tws.append(tw)
                    wrs.append(wr)
                    npl.append(pl["count"])
                    lpl.append(pl["length_nm"])
                    tpl.append(pl["tip_nm"])
                ca = self._catenation(pos)
                if self.braid and abs(ca - ang[i]) > 0.5:
                    e.blow_up(f"catenation {ca:.3f} no longer follows the bead angle "
                              f"{ang[i]:.3f} turns: the strands passed through each other",
                              None, None)
                fsteps.append(e.step)
                cats.append(ca)
                frames.append(pos.astype(np.float32))
        extra = {}
        if self.twisted:
            extra = dict(twist_torque_pN_nm=twt, twist=np.array(tws), writhe=np.array(wrs),
                         plectonemes=np.array(npl, float), plectoneme_length_nm=np.array(lpl),
                         plectoneme_tip_nm=np.array(tpl))
        return PointResult(target, step, ext, tor, ang, np.array(fsteps), np.array(cats),
                           np.array(frames).reshape(len(frames), -1, 3), **extra)
