"""Audit of the pointwise two-scale BRDF's diffracted part against the independent facet-frame reference.

Prints, for aluminium with ABC nano-roughness (σ = 10 nm, B = 2 µm, C = 2.6) at 550 nm and a Beckmann micro NDF
α ∈ {0.1, 0.3}, the ratio

    TwoScaleBRDF(...).eval_parts(wi, wo, λ)["diffraction"]  /  reference facet integral

at in-plane (θi → θo) 30→60, 30→75, 60→80°. The reference (``tests/twoscale_reference.py``, written from Walter et
al. 2007 and Heitz 2014, not from the package) integrates the nano lobe in every facet's own frame:

    f_diff(i, o) = ∫ |i·m| |o·m| / (|i·n| |o·n|) · f_nano(i_m, o_m; λ) · G2(i, o, m) · D(m) dω_m

by Monte Carlo (balance-heuristic mixture of NDF and half-vector sampling), with the standard error.

The nano lobe f_nano is the package's own, through its public API only:
* ``diffraction="kirchhoff"`` (the default): ``waveoptics.scatter.scattered_lobe(wi, wo, λ, psd, F=F(θ_d))`` with
  F the unpolarized Fresnel reflectance at the facet-frame half-vector angle (Fresnel written in the reference, ε
  from ``waveoptics.scatter.permittivity``);
* ``diffraction="rayleigh-rice"``: the reference's own first-order perturbation lobe (Elson & Bennett 1979, Q_ss,
  Q_sp, Q_ps, Q_pp), which the script first checks against ``waveoptics.scatter.rayleigh_rice_lobe``.
A first row at α = 0.003 checks that the package's two-scale model reduces to that nano lobe (ratio → 1), i.e. that
the reference is fed the same lobe the model convolves.

Usage: ``PYTHONPATH=$PWD python scripts/audit_twoscale.py [--samples N] [--seed S]``.

References
----------
B. Walter et al., EGSR 2007 (facets carrying a BRDF); E. Heitz, JCGT 3(2) 2014 (G2); E. Veach, PhD thesis 1997
§9.2 (balance heuristic); N. Holzschuch, R. Pacanowski, ACM TOG 36(4) 2017 (two scales); docs/physics.md §4, §7.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

import waveoptics as wo

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
import twoscale_reference as R  # noqa: E402

LAM = 550.0
GEOMETRIES = ((30.0, 60.0), (30.0, 75.0), (60.0, 80.0))
ALPHAS = (0.1, 0.3)
#: the nano lobe's width in direction cosines, λ / B, for the half-vector sampling technique
NANO_WIDTH = LAM / 2000.0


def nano_lobes(psd, material):
    """The package's nano lobes as reference callables f_nano(wi, wo, λ) in the facet frame."""
    eps = complex(wo.scatter.permittivity(material, LAM))
    ref_psd = R.abc_psd(psd.sigma * 1e9, psd.B * 1e9, psd.C)

    def kirchhoff(a, b, lam):
        cd = np.clip(np.sum(R.half_vector(a, b) * a, axis=-1), 0.0, 1.0)
        return wo.scatter.scattered_lobe(a, b, lam, psd, F=R.fresnel_R(cd, eps), diffraction="kirchhoff")

    return {"kirchhoff": kirchhoff, "rayleigh-rice": R.rayleigh_rice_nano(ref_psd, eps)}, eps, ref_psd


def check_rayleigh_rice(psd, material, eps, ref_psd):
    """Largest relative difference between the package's and the reference's Rayleigh-Rice lobes."""
    rng = np.random.default_rng(0)
    wi = R.direction(rng.uniform(0, 85, 500), rng.uniform(0, 360, 500))
    wout = R.direction(rng.uniform(0, 85, 500), rng.uniform(0, 360, 500))
    a = wo.scatter.rayleigh_rice_lobe(wi, wout, LAM, psd, material)
    b = R.rayleigh_rice_brdf(wi, wout, LAM, ref_psd, eps)
    return float(np.max(np.abs(a / b - 1.0)))


def ratios(model, alpha, f_nano, psd, n_samples, seed):
    """Package diffracted part / reference facet integral at GEOMETRIES, and the ratio's standard error."""
    wi = R.direction([g[0] for g in GEOMETRIES])
    wout = R.direction([g[1] for g in GEOMETRIES], 180.0)
    brdf = wo.TwoScaleBRDF("aluminium", wo.brdf.Micro(alpha=alpha, ndf="beckmann"), nano=wo.brdf.Nano(model=psd),
                           diffraction=model)
    pkg = brdf.eval_parts(wi, wout, LAM)["diffraction"]
    ref, se = R.facet_integral(f_nano, wi, wout, LAM, alpha, "beckmann", nano_width=NANO_WIDTH,
                               n_samples=n_samples, seed=seed)
    return pkg / ref, pkg / ref * se / ref


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=100_000, help="Monte Carlo samples per direction pair")
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args(argv)
    psd = wo.surfaces.PSDModel("abc", 10e-9, B=2e-6, C=2.6)
    material = wo.get_material("aluminium")
    lobes, eps, ref_psd = nano_lobes(psd, material)
    print(f"Al at {LAM:g} nm (n = {np.sqrt(eps):.4f}), ABC σ = 10 nm, B = 2 µm, C = 2.6; Beckmann micro NDF; "
          f"{args.samples} samples per pair, seed {args.seed}")
    print(f"package rayleigh_rice_lobe vs reference Rayleigh-Rice: max |ratio − 1| = "
          f"{check_rayleigh_rice(psd, material, eps, ref_psd):.1e} over 500 random pairs")
    head = "  ".join(f"{a:g}→{b:g}°".rjust(15) for a, b in GEOMETRIES)
    for model in ("kirchhoff", "rayleigh-rice"):
        print(f"\ndiffraction={model!r}: package diffracted part / reference facet integral (± 1 s.e.)")
        print(f"{'α':>6}  {head}")
        for alpha in (0.003, *ALPHAS):
            r, s = ratios(model, alpha, lobes[model], psd, args.samples, args.seed)
            print(f"{alpha:>6g}  " + "  ".join(f"{x:8.3f} ± {e:.3f}" for x, e in zip(r, s)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
