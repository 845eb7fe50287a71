"""Where the 1-D Kirchhoff and first-order perturbation models hold against the rigorous method of moments: the
table ``validity_map.json`` beside this file, written by ``scripts/docs_validity_map.py`` (the page
docs/validity-map.md): the planner's choice between the tangent-plane (Kirchhoff) and the first-order perturbation
(Rayleigh-Rice) nano lobe is the model with the smaller measured error in the cells nearest the scene
(:func:`choose_model`).

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
from dataclasses import dataclass
from pathlib import Path

__all__ = ["load_validity_map", "model_error", "MAP_MODELS", "map_medium", "ModelChoice", "choose_model"]

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


#: the map's model names and the project's diffraction models they stand for
MAP_MODELS = {"kirchhoff": "kirchhoff", "spm1": "rayleigh-rice"}


def map_medium(material) -> str:
    """The map's medium for a material: 'conductor' without one (F = 1), 'aluminium' for a metal (the map's real
    metal), 'glass' for a dielectric."""
    if material is None:
        return "conductor"
    return "aluminium" if bool(getattr(material, "is_metal", False)) else "glass"


@dataclass(frozen=True)
class ModelChoice:
    """The model :func:`choose_model` picked, with the evidence: per map model its worst noise-corrected relative
    L2 error over the cells consulted, and those cells as (θᵢ°, kσ, kℓ)."""

    model: str
    errors: dict
    cells: tuple
    medium: str
    noise_floor: float

    def note(self) -> str:
        """One sentence for the plan: which cells decided and what was measured there."""
        cells = ", ".join(f"θ_i {t:g}°, kσ {ks:g}, kℓ {kl:g}" for t, ks, kl in self.cells)
        errs = ", ".join(f"{MAP_MODELS[m]} {100 * e:.0f} %" for m, e in sorted(self.errors.items()))
        return (f"validity map (docs/validity-map.md, method of moments on 1-D Gaussian surfaces, {self.medium}, s and "
                f"p): cells {cells}: worst error {errs} (sampling noise {100 * self.noise_floor:.0f} %)")


def choose_model(material, k_sigma: float, k_ell: float, thetas_deg) -> ModelChoice:
    """The diffraction model with the smaller measured error where the scene lies on the map: for each map model,
    the worst noise-corrected relative L2 error (``l2_corrected``) over s and p and over the incidences *thetas_deg*
    (each to its nearest map incidence, kσ and kℓ to their nearest cells in log scale, :func:`model_error`).
    Rayleigh-Rice is chosen when its error is smaller than Kirchhoff's by more than the cells' sampling noise
    floor (a smaller difference is not resolved by the map); otherwise Kirchhoff.

    Parameters
    ----------
    material : Material or None
        The facet's material (None: F = 1, the perfect conductor).
    k_sigma : float
        k σ_rel, the relevant rms height times 2π/λ (dimensionless).
    k_ell : float
        k ℓ, the correlation length (Gaussian C(r) = σ² exp(−r²/ℓ²)) times 2π/λ; for other PSDs their length
        scale stands in for ℓ, an approximation the plan's note states.
    thetas_deg : sequence of float
        Incidences the scene shows (degrees).
    """
    medium = map_medium(material)
    thetas = sorted({min(load_validity_map()["grid"]["theta_deg"], key=lambda g: abs(g - float(t)))
                     for t in thetas_deg})
    errors, cells, noise = {}, set(), 0.0
    for m in MAP_MODELS:
        worst = 0.0
        for t in thetas:
            for pol in ("s", "p"):
                e = model_error(m, medium, pol, t, k_sigma, k_ell)
                worst = max(worst, float(e["l2_corrected"]))
                noise = max(noise, float(e["noise_floor"]))
                cells.add((e["theta_deg"], e["k_sigma"], e["k_ell"]))
        errors[m] = worst
    # Kirchhoff (the model whose limits are measured) unless first order is better by more than the map resolves
    model = "rayleigh-rice" if errors["kirchhoff"] - errors["spm1"] > noise else "kirchhoff"
    return ModelChoice(model, errors, tuple(sorted(cells)), medium, noise)
