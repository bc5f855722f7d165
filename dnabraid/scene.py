"""Scenes: what is simulated, as frozen dataclasses that round-trip through TOML.

A scene is built from a built-in name (``braid``, ``tether``, ``plectoneme``) or a TOML file, then
modified by flat ``KEY=VALUE`` overrides. Everything is validated here, at the entry
point, and errors say which key, what was expected and what came.
"""

from __future__ import annotations

import ast
import dataclasses
import math
import os
import sys
from typing import Any

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

from . import forcefield


class SceneError(ValueError):
    """A scene could not be built: unknown key, bad value or impossible geometry."""


# Key metadata: name -> (unit, help). Defaults live on the dataclass.
KEY_DOCS: dict[str, tuple[str, str]] = {
    "scene": ("", "scene kind: braid | tether | plectoneme | knot"),
    "force_pN": ("pN", "constant force pulling the magnetic bead up (> 0)"),
    "turns": ("turns", "list of bead turn values n (catenation imposed by the rotational trap)"),
    "salt_mM": ("mM", "monovalent salt; sets the effective DNA diameter (Stigter 1977)"),
    "length_nm": ("nm", "contour length of each DNA molecule"),
    "bead_spacing_nm": ("nm", "distance b between beads along a strand"),
    "tether_separation_nm": ("nm", "distance between the two tether points (surface and bead)"),
    "persistence_nm": ("nm", "bending persistence length"),
    "temperature_K": ("K", "temperature"),
    "steps": ("steps", "sampling steps per turn value (after equilibration)"),
    "equilibration_steps": ("steps", "equilibration steps after each change of turns"),
    "turn_rate": ("turns/step", "speed at which the trap angle is ramped between turn values"),
    "seed": ("", "random seed of the Brownian integrator"),
    "diameter_nm": ("nm", "effective DNA diameter; 0 = from salt (Stigter 1977 table)"),
    "stretch_modulus_pN": ("pN", "stretch modulus S of the double helix (bond stiffness S/b)"),
    "stretch": ("", "'bonds' (harmonic springs) or 'constraints' (rigid bonds)"),
    "bead_radius_nm": ("nm", "radius of the magnetic bead (sets its physical friction)"),
    "bead_friction_factor": ("", "bead friction used / physical Stokes friction (<1 speeds sampling)"),
    "trap_stiffness_pN_nm": ("pN nm", "rotational trap: U = -K cos(phi - 2 pi n)"),
    "report_interval": ("steps", "steps between observable samples"),
    "frame_interval": ("steps", "steps between trajectory frames (multiple of report_interval)"),
    "surface": ("", "true: a wall at z = 0 keeps DNA above the surface"),
    "timestep_safety": ("", "time step = safety x 2 / (mobility x largest stiffness)"),
    "alpha": ("pN", "chiral strength alpha of phi = alpha tan(eta/2) (energy per contact length, "
              "pN = pN nm/nm; 1 kT/nm = 4.11 pN); 0 = no chiral term; 'salt' = the estimate at "
              "salt_mM from forcefields/chiral.toml; > 0 favours right-handed braids (n > 0)"),
    "twist_persistence_nm": ("nm", "twist persistence length C of torsionally constrained DNA "
                             "(plectoneme scene; Moroz & Nelson 1997, Bryant et al. 2003: "
                             "C ~ 100 nm; twist-stretch coupling is left out)"),
    "knot_n": ("", "knot scene: unknotting number n of the open (2, 2n+1) torus knot "
               "(1 trefoil, 2 cinquefoil, ...; seed 001)"),
    "tension_pN": ("pN", "knot scene: tension T pulling both ends"),
    "rod_radius_nm": ("nm", "knot scene: rod radius h (contact at 2h)"),
    "bending_stiffness_pN_nm2": ("pN nm^2", "knot scene: bending stiffness B = EI"),
    "start_loop_factor": ("", "knot scene: loop radius of the starting shape / sqrt(B / 2T) "
                          "(> 1 tightens, < 1 loosens; the bead contact pins sliding)"),
}

_KNOT_KEYS = {"knot_n", "tension_pN", "rod_radius_nm", "bending_stiffness_pN_nm2",
              "start_loop_factor", "bead_spacing_nm"}
_BRAID_KEYS = set(KEY_DOCS) - {"scene", "twist_persistence_nm"} - _KNOT_KEYS | {"bead_spacing_nm"}
_TETHER_KEYS = _BRAID_KEYS - {"tether_separation_nm", "trap_stiffness_pN_nm", "turn_rate"}
_PLECTONEME_KEYS = _TETHER_KEYS | {"trap_stiffness_pN_nm", "turn_rate", "twist_persistence_nm"}

#: Scenes whose DNA is torsionally constrained (a frame per bond and a twist energy).
TWISTED_SCENES = ("plectoneme",)


def _default_turns():
    return (-4.0, -3.0, -2.0, -1.0, 0.0, 1.0, 2.0, 3.0, 4.0)


@dataclasses.dataclass(frozen=True)
class Scene:
    """A resolved tweezer scene (all lengths nm, forces pN, energies pN nm).

    Defaults are for nicked DNA in 150 mM NaCl at 25 C. ``scene='braid'``: two nicked
    molecules between a surface and a magnetic bead, turned ``turns`` times;
    ``scene='tether'``: one molecule, pulled, not turned; ``scene='plectoneme'``: one
    torsionally constrained (un-nicked) molecule, pulled and turned (twist, writhe,
    plectonemes).
    """

    scene: str = "braid"
    force_pN: float = 2.0
    turns: tuple = dataclasses.field(default_factory=_default_turns)
    salt_mM: float = 150.0
    length_nm: float = 200.0
    bead_spacing_nm: float = 5.0
    tether_separation_nm: float = 40.0
    persistence_nm: float = 50.0
    temperature_K: float = 298.15
    steps: int = 180000
    equilibration_steps: int = 40000
    turn_rate: float = 5e-5
    seed: int = 1
    diameter_nm: float = 0.0
    stretch_modulus_pN: float = 1100.0
    stretch: str = "bonds"
    bead_radius_nm: float = 500.0
    bead_friction_factor: float = 0.01
    trap_stiffness_pN_nm: float = 20000.0
    report_interval: int = 100
    frame_interval: int = 5000
    surface: bool = True
    timestep_safety: float = 0.3
    alpha: float = 0.0
    twist_persistence_nm: float = 100.0
    knot_n: int = 1
    tension_pN: float = 0.8
    rod_radius_nm: float = 1.0
    bending_stiffness_pN_nm2: float = 1000.0
    start_loop_factor: float = 1.0

    # -- derived ---------------------------------------------------------------
    @property
    def n_beads(self) -> int:
        """Beads per strand (both ends included)."""
        return int(round(self.length_nm / self.bead_spacing_nm)) + 1

    @property
    def n_strands(self) -> int:
        return 2 if self.scene == "braid" else 1

    @property
    def twisted(self) -> bool:
        """True for torsionally constrained DNA (frames and a twist energy are built)."""
        return self.scene in TWISTED_SCENES

    @property
    def turned(self) -> bool:
        """True when the rotational trap turns the bead (braid, plectoneme)."""
        return self.scene in ("braid", "plectoneme")

    @property
    def effective_diameter_nm(self) -> float:
        if self.diameter_nm > 0:
            return float(self.diameter_nm)
        return forcefield.salt_parameters(self.salt_mM).diameter_nm

    @property
    def kT(self) -> float:
        from .units import kT

        return kT(self.temperature_K)

    def allowed_keys(self) -> set:
        return allowed_keys(self.scene)

    def to_dict(self) -> dict:
        d = {}
        for f in dataclasses.fields(self):
            if f.name in self.allowed_keys() or f.name == "scene":
                v = getattr(self, f.name)
                d[f.name] = list(v) if isinstance(v, tuple) else v
        return d

    def to_toml(self) -> str:
        return dumps_toml(self.to_dict())


def allowed_keys(kind: str) -> set:
    if kind == "braid":
        return set(_BRAID_KEYS)
    if kind == "tether":
        return set(_TETHER_KEYS)
    if kind == "plectoneme":
        return set(_PLECTONEME_KEYS)
    if kind == "knot":
        return set(_KNOT_KEYS)
    raise SceneError(f"unknown scene {kind!r}; built-in scenes are: braid, tether, plectoneme, knot")


BUILTIN = {
    "braid": {},
    "tether": {"turns": [0.0], "force_pN": 1.0, "length_nm": 300.0},
    "plectoneme": {"turns": [0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0], "force_pN": 1.0,
                   "length_nm": 300.0},
    "knot": {"bead_spacing_nm": 0.5},
}

SCENE_HELP = {
    "braid": "two nicked DNA molecules between a surface and a magnetic bead, braided by "
    "turning the bead: extension, torque and catenation against turns",
    "tether": "one nicked DNA molecule between surface and bead under force: force-extension",
    "knot": "an open (2, 2n+1) knot (trefoil, cinquefoil, ...) tied in an elastic rod pulled "
    "by a tension, relaxed at zero temperature (no tweezer bead, surface or electrostatics): "
    "loop radius, braid length and wave number against the continuum theory (seeds 001, 002)",
    "plectoneme": "one torsionally constrained DNA molecule between surface and bead under "
    "force, turned n times: extension and torque against turns (the hat curve), buckling, "
    "twist, writhe and plectonemes",
}


def dumps_toml(d: dict) -> str:
    """Minimal TOML writer for flat tables of numbers, strings, bools and lists."""
    lines = []
    for k, v in d.items():
        lines.append(f"{k} = {_toml_value(v)}")
    return "\n".join(lines) + "\n"


def _toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        return repr(v)
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    raise TypeError(f"cannot write {type(v).__name__} to TOML")


def parse_value(text: str) -> Any:
    """Parse a ``--set`` value: TOML-ish literals (numbers, lists, true/false, strings)."""
    t = text.strip()
    if t.lower() in ("true", "false"):
        return t.lower() == "true"
    try:
        return ast.literal_eval(t)
    except (ValueError, SyntaxError):
        return t


def _coerce(key: str, value: Any, field_type: str):
    """Coerce ``value`` to the field's type, raising SceneError with the key named."""
    unit = KEY_DOCS.get(key, ("", ""))[0]
    where = f"{key}" + (f" (in {unit})" if unit else "")
    if key == "turns":
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            value = [value]
        if not isinstance(value, (list, tuple)) or not value:
            raise SceneError(f"{where}: expected a non-empty list of numbers, got {value!r}")
        try:
            out = tuple(float(x) for x in value)
        except (TypeError, ValueError) as exc:
            raise SceneError(f"{where}: expected a list of numbers, got {value!r}") from exc
        if any(not math.isfinite(x) for x in out):
            raise SceneError(f"{where}: turn values must be finite, got {value!r}")
        if len(set(out)) != len(out):
            raise SceneError(f"{where}: turn values must be distinct, got {value!r}")
        return out
    if field_type == "bool":
        if isinstance(value, bool):
            return value
        raise SceneError(f"{where}: expected true or false, got {value!r}")
    if field_type == "int":
        if isinstance(value, bool) or not isinstance(value, (int, float)) or int(value) != value:
            raise SceneError(f"{where}: expected an integer, got {value!r}")
        return int(value)
    if field_type == "float":
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise SceneError(f"{where}: expected a number, got {value!r}")
        if not math.isfinite(value):
            raise SceneError(f"{where}: expected a finite number, got {value!r}")
        return float(value)
    if field_type == "str":
        if not isinstance(value, str):
            raise SceneError(f"{where}: expected a string, got {value!r}")
        return value
    raise SceneError(f"{key}: unsupported type")  # pragma: no cover


_FIELD_TYPES = {f.name: (f.type if isinstance(f.type, str) else f.type.__name__)
                for f in dataclasses.fields(Scene)}


def make_scene(base: str | os.PathLike = "braid", overrides: dict | None = None) -> Scene:
    """Build and validate a scene.

    Parameters
    ----------
    base : str or path
        A built-in scene name (see ``BUILTIN``) or a path to a TOML file.
    overrides : dict, optional
        Flat keys (see ``KEY_DOCS``) overriding the base.

    Raises
    ------
    SceneError
        For an unknown scene, key, a bad value or an impossible geometry.
    FileNotFoundError
        For a missing TOML file.
    """
    values: dict = {}
    base_s = os.fspath(base)
    if base_s in BUILTIN:
        kind = base_s
        values.update(BUILTIN[kind])
    elif base_s.endswith(".toml") or os.path.sep in base_s:
        if not os.path.isfile(base_s):
            raise FileNotFoundError(f"scene file {base_s!r} does not exist")
        with open(base_s, "rb") as fh:
            try:
                data = tomllib.load(fh)
            except tomllib.TOMLDecodeError as exc:
                raise SceneError(f"scene file {base_s!r} is not valid TOML: {exc}") from exc
        kind = data.pop("scene", "braid")
        if kind not in BUILTIN:
            raise SceneError(f"{base_s}: unknown scene {kind!r}; built-in scenes are: "
                             + ", ".join(BUILTIN))
        values.update(BUILTIN[kind])
        values.update(data)
    else:
        raise SceneError(f"unknown scene {base_s!r}: give one of the built-in scenes ("
                         + ", ".join(BUILTIN) + ") or a path to a .toml file")
    if overrides:
        values.update(overrides)
    allowed = allowed_keys(kind)
    unknown = sorted(set(values) - allowed)
    if unknown:
        raise SceneError(
            f"unknown key(s) {', '.join(unknown)} for scene {kind!r}; allowed keys: "
            + ", ".join(sorted(allowed)))
    if isinstance(values.get("alpha"), str):
        if values["alpha"].strip().lower() != "salt":
            raise SceneError(f"alpha (in pN): expected a number or 'salt', got {values['alpha']!r}")
        salt = _coerce("salt_mM", values.get("salt_mM", Scene.salt_mM), "float")
        if not salt > 0:
            raise SceneError(f"salt_mM={salt!r} mM: salt must be > 0 mM")
        values["alpha"] = forcefield.chiral_parameters(salt)["alpha_pN"]
    coerced = {k: _coerce(k, v, _FIELD_TYPES[k]) for k, v in values.items()}
    scene = Scene(scene=kind, **coerced)
    validate(scene)
    return scene


def passage_barrier_kT(bead_spacing_nm: float, diameter_nm: float) -> float:
    """Excluded-volume barrier (kT) against two strands passing through each other.

    Worst case: two bonds crossing at right angles through each other's midpoints; the
    four inter-strand bead pairs are then b / sqrt(2) apart and each costs the WCA energy
    with epsilon = kT and sigma = diameter.
    """
    r = bead_spacing_nm / math.sqrt(2.0)
    rc = 2 ** (1 / 6) * diameter_nm
    if r >= rc:
        return 0.0
    sr6 = (diameter_nm / r) ** 6
    return 4.0 * (4.0 * (sr6 * sr6 - sr6) + 1.0)


#: Smallest barrier (in kT) against strand passage that a scene may have.
MIN_PASSAGE_BARRIER_KT = 20.0


def max_bead_spacing_nm(diameter_nm: float) -> float:
    """Largest bead spacing whose passage barrier is at least MIN_PASSAGE_BARRIER_KT."""
    lo, hi = 1e-3 * diameter_nm, 10 * diameter_nm
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        if passage_barrier_kT(mid, diameter_nm) >= MIN_PASSAGE_BARRIER_KT:
            lo = mid
        else:
            hi = mid
    return lo


def validate(s: Scene) -> None:
    """Check values and geometry; raise SceneError naming the key and what is allowed."""
    def need(cond, key, msg):
        if not cond:
            unit = KEY_DOCS[key][0]
            raise SceneError(f"{key}={getattr(s, key)!r}{' ' + unit if unit else ''}: {msg}")

    if s.scene == "knot":
        validate_knot(s, need)
        return
    need(s.force_pN > 0, "force_pN", "the pulling force must be > 0 pN")
    need(s.force_pN <= 100, "force_pN", "above ~65 pN DNA overstretches; this model allows <= 100 pN")
    need(s.salt_mM > 0, "salt_mM", "salt must be > 0 mM")
    need(s.salt_mM <= 5000, "salt_mM", "salt must be <= 5000 mM")
    need(s.length_nm > 0, "length_nm", "must be > 0")
    need(s.bead_spacing_nm > 0, "bead_spacing_nm", "must be > 0")
    need(s.n_beads >= 3, "length_nm", f"gives only {s.n_beads} beads; need >= 3 "
         f"(length >= 2 x bead_spacing_nm)")
    need(abs(s.n_beads - 1 - s.length_nm / s.bead_spacing_nm) < 1e-6, "length_nm",
         f"must be a whole multiple of bead_spacing_nm={s.bead_spacing_nm}")
    need(s.persistence_nm > 0, "persistence_nm", "must be > 0")
    need(s.persistence_nm >= s.bead_spacing_nm, "persistence_nm",
         "must be >= bead_spacing_nm (a bead chain cannot resolve a shorter persistence)")
    need(150 <= s.temperature_K <= 400, "temperature_K", "must be between 150 and 400 K")
    need(s.steps >= s.report_interval, "steps", f"must be >= report_interval={s.report_interval}")
    need(s.equilibration_steps >= 0, "equilibration_steps", "must be >= 0")
    need(s.report_interval >= 1, "report_interval", "must be >= 1")
    need(s.frame_interval >= s.report_interval and s.frame_interval % s.report_interval == 0,
         "frame_interval", f"must be a multiple of report_interval={s.report_interval}")
    need(s.diameter_nm >= 0, "diameter_nm", "must be >= 0 (0 = from salt)")
    need(s.stretch_modulus_pN > 10 * s.force_pN, "stretch_modulus_pN",
         "must be much larger than the force (> 10 x force_pN)")
    need(s.stretch in ("bonds", "constraints"), "stretch", "allowed: 'bonds', 'constraints'")
    need(s.bead_radius_nm > 0, "bead_radius_nm", "must be > 0")
    need(0 < s.bead_friction_factor <= 1, "bead_friction_factor", "must be in (0, 1]")
    need(s.trap_stiffness_pN_nm > 0, "trap_stiffness_pN_nm", "must be > 0")
    need(0 < s.turn_rate <= 0.01, "turn_rate", "must be in (0, 0.01] turns per step")
    need(0 < s.timestep_safety <= 0.9, "timestep_safety", "must be in (0, 0.9]")
    need(s.seed >= 0, "seed", "must be >= 0")
    need(abs(s.alpha) <= 50.0, "alpha",
         "|alpha| must be <= 50 pN (~12 kT/nm; literature estimates are 0.01-1.5 pN, "
         "forcefields/chiral.toml)")
    if s.scene == "tether":
        need(all(t == 0 for t in s.turns), "turns",
             "a nicked single tether cannot hold turns; use turns=[0]")
        need(len(s.turns) == 1, "turns", "a tether has one turn value, [0]")
    d = s.effective_diameter_nm
    barrier = passage_barrier_kT(s.bead_spacing_nm, d)
    if s.twisted:
        need(s.twist_persistence_nm >= s.bead_spacing_nm, "twist_persistence_nm",
             "must be >= bead_spacing_nm (a bead chain cannot resolve a shorter twist persistence)")
        need(s.twist_persistence_nm <= 1000.0, "twist_persistence_nm",
             "must be <= 1000 nm (DNA: ~100 nm)")
    # a braid's strands, a long tether's loops and a plectoneme's branches must not pass
    # through each other (for twisted DNA that would change the linking number)
    if s.n_strands == 2 or s.twisted or s.length_nm > 3 * s.persistence_nm:
        need(barrier >= MIN_PASSAGE_BARRIER_KT, "bead_spacing_nm",
             f"too coarse for the effective DNA diameter {d:.2f} nm at {s.salt_mM} mM salt: "
             f"strands could pass through each other (barrier {barrier:.1f} kT < "
             f"{MIN_PASSAGE_BARRIER_KT} kT). Use bead_spacing_nm <= {max_bead_spacing_nm(d):.2f}")
    if s.scene == "braid":
        need(s.tether_separation_nm >= d, "tether_separation_nm",
             f"must be >= the effective diameter {d:.2f} nm (the tethers would overlap)")
        need(s.tether_separation_nm < s.length_nm, "tether_separation_nm",
             f"must be < length_nm={s.length_nm} (tethers farther apart than the strands are "
             "long cannot be bridged)")
        # Lock-up (seed 000, slide 18): a two-ply of contact distance d = 2r cannot wind
        # past theta = 45 deg; n = L sin(theta) / (2 pi r) turns of the whole length L is
        # the most any braid of these molecules can hold.
        n_lock = s.length_nm / (math.sqrt(2.0) * math.pi * d)
        need(max(abs(t) for t in s.turns) <= n_lock, "turns",
             f"|turns| must be <= {n_lock:.2f}: more turns than a {s.length_nm} nm braid of "
             f"diameter {d:.2f} nm can hold at the 45-degree lock-up (L / (sqrt(2) pi d))")


#: Largest eps = sqrt(h / R) of the knot scene: seed 002 (Fig. 6) computes a tight trefoil at
#: eps = 0.52; beyond, the loop is shorter than the braid around it.
MAX_KNOT_EPS = 0.55
#: Largest bead count of the knot scene (its Newton solve is ~O(N) per iteration).
MAX_KNOT_BEADS = 20000


def validate_knot(s: Scene, need) -> None:
    need(1 <= s.knot_n <= 10, "knot_n", "must be 1 (trefoil) ... 10")
    need(s.tension_pN > 0, "tension_pN", "must be > 0 pN")
    need(s.rod_radius_nm > 0, "rod_radius_nm", "must be > 0")
    need(s.bending_stiffness_pN_nm2 > 0, "bending_stiffness_pN_nm2", "must be > 0")
    need(0.5 <= s.start_loop_factor <= 2.0, "start_loop_factor", "must be in [0.5, 2]")
    need(s.bead_spacing_nm <= s.rod_radius_nm, "bead_spacing_nm",
         f"must be <= rod_radius_nm={s.rod_radius_nm} (coarser beads let the strands slip "
         "through each other and corrugate the contact)")
    R = math.sqrt(s.bending_stiffness_pN_nm2 / (2.0 * s.tension_pN))
    eps = math.sqrt(s.rod_radius_nm / R)
    need(eps <= MAX_KNOT_EPS, "tension_pN",
         f"gives eps = sqrt(h/R) = {eps:.3f} > {MAX_KNOT_EPS} (loop radius R = sqrt(B/2T) = "
         f"{R:.3g} nm): tighter than the tightest elastic knot computed (seed 002, eps 0.52); "
         "lower the tension")
    length = 2 * math.pi * R * 1.5 + 3.0 * math.sqrt(s.bending_stiffness_pN_nm2 / s.tension_pN) \
        + 4 * (s.knot_n + 1) * 3.5 * math.sqrt(2 * s.rod_radius_nm * R)
    beads = length / s.bead_spacing_nm
    need(beads <= MAX_KNOT_BEADS, "tension_pN",
         f"needs ~{beads:.0f} beads (> {MAX_KNOT_BEADS}): the knot is too loose for this "
         "bead spacing; raise the tension or bead_spacing_nm")
