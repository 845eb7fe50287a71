"""The planner's diffraction model is the one the validity map measured as closer to the rigorous solution.

The map (``waveoptics/planning/validity_map.json``, written by ``scripts/docs_validity_map.py`` from the method of
moments, docs/validity-map.md) is read here directly; the nearest cell and the comparison are written in this test.
Three scenes: a rough aluminium surface at 30° (Kirchhoff's domain, first order fails), a smooth glass surface lit at
70° (first order holds, Kirchhoff's p light is off by 25 %), and a smooth aluminium surface at 30° (both hold within
the map's noise, so the planner keeps Kirchhoff)."""
import json
import math
from pathlib import Path

import pytest

from waveoptics.planning import plan_scene
from waveoptics.planning.scene import parse

TABLE = json.loads((Path(__file__).resolve().parents[1] / "waveoptics" / "planning" / "validity_map.json")
                   .read_text())


def _nearest(model, medium, pol, theta, ks, kl):
    rows = [e for e in TABLE["entries"] if (e["model"], e["medium"], e["polarization"]) == (model, medium, pol)]
    t = min({e["theta_deg"] for e in rows}, key=lambda x: abs(x - theta))
    rows = [e for e in rows if e["theta_deg"] == t]
    return min(rows, key=lambda e: abs(math.log(e["k_sigma"] / ks)) + abs(math.log(e["k_ell"] / kl)))


def _expected(medium, ks, kl, theta):
    err = {m: max(_nearest(m, medium, p, theta, ks, kl)["l2_corrected"] for p in "sp") for m in ("kirchhoff", "spm1")}
    noise = max(_nearest(m, medium, p, theta, ks, kl)["noise_floor"] for m in err for p in "sp")
    return ("rayleigh-rice" if err["kirchhoff"] - err["spm1"] > noise else "kirchhoff"), err


def _scene(material, sigma_nm, theta):
    mat = {"name": "m", "roughness": 0.05, "ndf": "ggx", "nano": {"statistics": f"gaussian:sigma={sigma_nm}nm,corr_length=2um"}}
    mat.update(material)
    return parse({"name": "t", "materials": [mat],
                  "lights": [{"name": "l", "spd": "D65", "directions_deg": [[theta, 0]]}],
                  "view": {"directions_deg": [[theta, 180]]}, "output": {"rgb_images": False, "tables": True}})


@pytest.mark.parametrize("material, medium, sigma_nm, theta", [({"material": "Al"}, "aluminium", 100.0, 30.0),
                                                               ({"ior": 1.5}, "glass", 2.0, 70.0),
                                                               ({"material": "Al"}, "aluminium", 2.0, 30.0)])
def test_planner_takes_the_model_with_the_smaller_measured_error(material, medium, sigma_nm, theta):
    e = plan_scene(_scene(material, sigma_nm, theta), force={"diffraction": True}).entries[0]
    lam = float(min(e.wavelengths_nm))
    k = 2 * math.pi / (lam * 1e-9)
    # Gaussian T = 2 µm: all of σ lies in the propagating band at these wavelengths, so σ_rel = σ and ℓ = T
    expected, err = _expected(medium, k * sigma_nm * 1e-9, k * 2e-6, theta)
    assert e.diffraction == expected, (err, e.reasons)
    note = next(r for r in e.reasons if r.startswith("diffraction model"))
    assert "validity map" in note and medium in note
    if medium == "glass":          # first order holds, Kirchhoff's p light does not: the map's switch
        assert expected == "rayleigh-rice"
    elif sigma_nm > 50:            # kσ ≈ 1.6: first order fails
        assert expected == "kirchhoff" and err["spm1"] > 1.0
