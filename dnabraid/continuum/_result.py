"""Results of continuum problems: numerical failure is data, not an exception."""

from __future__ import annotations

import dataclasses
import math
from typing import Any


@dataclasses.dataclass
class ContinuumResult:
    """Outcome of one continuum solve (modelled on scipy's ``BVPResult``).

    Attributes
    ----------
    success : bool
        True when the solver converged and the solution passed its checks.
    status : int
        0 converged; 1 max nodes / iterations exceeded; 2 singular Jacobian or
        invalid step; 3 outside the model's domain (e.g. past lock-up); 4 other.
    message : str
        Human-readable reason, always set (also on success).
    values : dict
        The physical outputs (named with units in the key, e.g. ``"torque_pN_nm"``)
        or dimensionless ones for scaled problems.
    residual : float
        Largest residual of the solved equations (nan if not applicable).
    mesh_size : int
        Number of mesh nodes (or unknowns) used.
    wall_time_s : float
        Wall-clock time of the solve.
    solution : Any
        Raw solution object (e.g. a scipy ``BVPResult``) usable for continuation.
    """

    success: bool
    status: int
    message: str
    values: dict = dataclasses.field(default_factory=dict)
    residual: float = math.nan
    mesh_size: int = 0
    wall_time_s: float = 0.0
    solution: Any = None

    def __getitem__(self, key):
        return self.values[key]

    def to_dict(self) -> dict:
        """JSON-serialisable summary (without the raw solution)."""
        out = {
            "success": bool(self.success),
            "status": int(self.status),
            "message": str(self.message),
            "residual": float(self.residual),
            "mesh_size": int(self.mesh_size),
            "wall_time_s": float(self.wall_time_s),
        }
        for k, v in self.values.items():
            try:
                out[k] = float(v)
            except (TypeError, ValueError):
                out[k] = v
        return out
