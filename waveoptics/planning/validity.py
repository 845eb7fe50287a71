"""Where the 1-D Kirchhoff and first-order perturbation models hold against the rigorous method of moments: the
table ``validity_map.json`` beside this file, written by ``scripts/docs_validity_map.py`` (the page
docs/validity-map.md), for a planner to consult. Not used by the planner yet.

Each entry: model ('kirchhoff' or 'spm1'), medium ('conductor', 'aluminium', 'glass'), polarization, θᵢ (degrees),
kσ, kℓ (Gaussian correlation σ² exp(−τ²/ℓ²), k = 2π/λ), the relative L2 error of the model's incoherent scattering
coefficient against the Monte-Carlo mean (``l2``), the sampling noise floor of that mean (``noise_floor``: an
error below it is not resolved) and the albedo error (model − rigorous reflectance).

References
----------
.. [1] E. I. Thorsos, J. Acoust. Soc. Am. 83(1), 78–92, 1988 (the method and the Kirchhoff findings).
"""
from __future__ import annotations

import functools
import json
import math
from pathlib import Path

__all__ = ["load_validity_map", "model_error"]

_PATH = Path(__file__).resolve().parent / "validity_map.json"


@functools.lru_cache(maxsize=1)
def load_validity_map() -> dict:
    """The shipped table (module doc) as a dict with keys 'grid', 'entries' and the run's parameters."""
    return json.loads(_PATH.read_text())


def model_error(model: str, medium: str, polarization: str, theta_deg: float, k_sigma: float,
                k_ell: float) -> dict:
    """The entry of the table nearest to (θᵢ, kσ, kℓ) for *model*, *medium* and *polarization* (nearest in θᵢ,
    then in log kσ and log kℓ); its 'theta_deg', 'k_sigma' and 'k_ell' say which cell answered."""
    rows = [e for e in load_validity_map()["entries"]
            if (e["model"], e["medium"], e["polarization"]) == (model, medium, polarization)]
    if not rows:
        raise KeyError(f"no entry for model {model!r}, medium {medium!r}, polarization {polarization!r}")
    return min(rows, key=lambda e: (abs(e["theta_deg"] - theta_deg),
                                    abs(math.log(e["k_sigma"] / k_sigma)) + abs(math.log(e["k_ell"] / k_ell))))
