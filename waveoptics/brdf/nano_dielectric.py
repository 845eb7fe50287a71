"""Nano-rough glass: the rough dielectric BSDF of :mod:`waveoptics.brdf.btdf` for a small micro-roughness α,
with first-order (Rayleigh-Rice) scatter of a nano-roughness PSD into both half-spaces (docs/physics.md §15).

    f(ω_i, ω_o) = A_R(μ_i) f_r^micro + A_T(μ_i) f_t^micro + f^RR(ω_i, ω_o)

f^RR is :func:`waveoptics.scatter.rr_bsdf` (reflection on either side, transmission across, air above and the
dielectric of real index η below). The nano-roughness takes its scattered energy from the coherent (specular)
light. The specular losses ΔR = R₀ − |r̄|² and ΔT = T₀ − (γ₂/γ₁)|t̄|² of each polarization come from the mean
(coherent) amplitudes r̄ = r₀ + r₂, t̄ = t₀ + t₂ of the second-order small-perturbation method (SPM2,
:func:`waveoptics.scatter.coherent_losses`: the boundary conditions expanded to O(σ²), integrals of the PSD against
kernels, evanescent orders included), and

    A_R = 1 − (ΔR_s + ΔR_p)/(R_s + R_p),   A_T = 1 − (ΔT_s + ΔT_p)/(T_s + T_p)

for unpolarized light. ΔR + ΔT is the first-order scatter TIS_R + TIS_T (the optical theorem; the two routes agree
within 1.5e-5 at the default nodes), so A_R R + A_T T + TIS = 1 for α → 0 (white furnace); at Brewster's angle the
reflected loss is the s light's alone, and beyond the critical angle all of it comes from R (A_T = 1: no coherent
T). Measured against the rigorous Rayleigh-method grating integrated over the PSD (tests/test_spm2.py,
tests/test_nano_dielectric.py; reference at 56 × 40 nodes, 500 nm, σ = 1 nm): ΔR and ΔT of s and p light within
0.05 % for a Gaussian PSD with ℓ = 1 µm (20°, 50°, 70°, 85° from air; 20°, 40°, 60° from glass) and within 0.4 %
for ℓ = 0.3 µm (the reference's own quadrature error is of that size); within 1 % of an ABC PSD (B = 1 µm, C = 3).
The Debye-Waller split this replaces was 17 % off in the reflected share at 70° from air (ℓ = 1 µm) and up to
210 % in one polarization's share (ℓ = 0.3 µm, 85°). The coherent transmittance is reciprocal: T̄ from air at θ₁
equals T̄ from glass at θ₂ (the Snell pair) within 1e-9. It holds to O((k σ)²) (A is linear in σ²).

Tables (:func:`nano_tables`): A_R, A_T, TIS_R, TIS_T on each side as functions of μ = |cosθ_i|, split at the
critical angle of light from the glass (μ_c = √(1 − 1/η²)), where the coherent transmission ends with a √ kink;
on each piece a cubic spline through nodes uniform in a variable t that crowds them quadratically towards the
kink (:func:`piece_variable`). Against the direct computation at cosines off the nodes (σ = 20 nm, ℓ = 1 and
0.3 µm, η = 1.5, 500 nm; 0.01° from the critical angle included) within 1e-4 (tests/test_nano_dielectric.py);
the linear interpolation on 16 Gauss-Legendre nodes it replaces was 4.4e-2 off in TIS_R at 40° in glass.

Where it holds: α → 0 (the nano lobes are evaluated about the macro normal, not per facet: for a rough α use the
two-scale model) and the smooth-surface limit of the nano-roughness, (4π n σ cosθ / λ)² ≪ 1 and small slopes.
Reciprocity: f^RR and the microfacet lobes are reciprocal with the η² factor of radiance, and so is the coherent
transmission A_T T; A_R scales one side's reflection and needs none.

A thin-film stack on the glass (an anti-reflection coating, ``material`` a :class:`waveoptics.materials.Stack` on a
dielectric substrate) makes each interface of the films rough with the stack's correlation: f^RR is then Elson's
first-order scatter of the rough stack into both half-spaces (:func:`waveoptics.scatter.rough_stack_bsdf`), the
losses the stack's second-order mean field (:func:`waveoptics.scatter.stack_coherent_losses`), R₀ and T₀ the flat
stack's, and the microfacet lobes carry the stack's R and T (:mod:`waveoptics.brdf.nano_interface`,
:mod:`waveoptics.brdf.facet_interface`). The white furnace of a lossless coated glass is then again
A_R R + A_T T + TIS = 1 for α → 0 (tests/test_coated_nano_glass.py).

References
----------
.. [1] B. Walter, S. R. Marschner, H. Li, K. E. Torrance, EGSR 2007 (the rough dielectric BSDF).
.. [2] J. M. Elson, Phys. Rev. B 30(10), 5460–5480, 1984; J. C. Stover, *Optical Scattering*, 3rd ed., SPIE 2012,
   ch. 4–5 (first-order scatter into both half-spaces).
.. [3] A. A. Maradudin, D. L. Mills, "Scattering and absorption of electromagnetic radiation by a semi-infinite
   medium in the presence of surface roughness", Phys. Rev. B 11(4), 1392–1415, 1975; J. T. Johnson,
   "Third-order small-perturbation method for scattering from dielectric rough surfaces", J. Opt. Soc. Am. A
   16(11), 2720–2736, 1999 (the second-order mean field; derivation in :mod:`waveoptics.scatter.spm2`).
"""
from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from scipy.interpolate import CubicSpline

from ..errors import FieldError
from ..scatter.spm2 import coherent_losses
from ..surfaces.psd import PSDModel
from .btdf import RoughDielectricBSDF
from .nano_interface import BareNano, check_film_psd, coherent_shares, nano_interface_of
from .mu_pieces import critical_cosine, piece_cosine, read_pieces, table_pieces
from .protocol import broadcast_incidence, broadcast_pair, lobe_choice

__all__ = ["check_perturbative", "NANO_MU_NODES", "NanoTables", "coherent_split", "nano_tables", "NanoRoughDielectricBSDF"]

#: intervals per piece of the coherent-factor and TIS tables (nodes uniform in the piece's variable t, both ends
#: included; :func:`table_pieces`)
NANO_MU_NODES = 12
#: samples in t per piece of the tables' cubic splines (read back by linear interpolation: 1e-7 of a spline)
NANO_DENSE_SAMPLES = 257
#: cosine of the grazing node (μ = 0 exactly has no incident wave)
MU_GRAZING = 1e-6
#: relative offset of a node at a critical cosine into its own piece (the two sides of the kink)
_KINK_OFFSET = 1e-9


#: the tabulated quantities (module doc)
TABLE_NAMES = ("A_R", "A_T", "tis_R", "tis_T")


@dataclass(frozen=True)
class NanoTables:
    """The coherent factors ``A_R``, ``A_T`` and the unpolarized first-order ``tis_R``, ``tis_T`` (module doc) for
    light from above (``up``) and from inside: on each side, per piece of μ (:func:`table_pieces`, split at the
    side's critical cosine ``mu_c_up`` / ``mu_c_down``), a cubic spline through :data:`NANO_MU_NODES` + 1 nodes
    uniform in the piece's variable t, sampled at ``t`` (:data:`NANO_DENSE_SAMPLES`). ``values[(name, up)]`` is
    (pieces, samples)."""

    mu_c_up: float
    mu_c_down: float
    t: np.ndarray
    values: dict

    def at(self, name: str, mu, up):
        """Table *name* (``A_R``, ``A_T``, ``tis_R``, ``tis_T``) at cosines *mu* on the side *up* (boolean): the
        piece of each μ (μ ≤ μ_c: the total-reflection side), linear in t between the spline's samples."""
        return np.where(up, read_pieces(mu, table_pieces(self.mu_c_up), self.t, self.values[(name, True)]),
                        read_pieces(mu, table_pieces(self.mu_c_down), self.t, self.values[(name, False)]))


def coherent_split(mu, n_i, n_o, psd, wavelength_nm):
    """(A_R, A_T) of unpolarized light at incidence cosine *mu* from a medium of index *n_i* onto *n_o* (real)
    with nano-roughness *psd* at *wavelength_nm* (nm): 1 − ΔR/R₀ and 1 − ΔT/T₀ summed over s and p, from the
    second-order mean field (:func:`waveoptics.scatter.coherent_losses`, module doc).

    References
    ----------
    .. [1] A. A. Maradudin, D. L. Mills, Phys. Rev. B 11(4), 1392–1415, 1975; J. T. Johnson, J. Opt. Soc. Am. A
       16(11), 2720–2736, 1999 (the second-order small-perturbation mean field).
    """
    return coherent_shares(coherent_losses(mu, n_i, n_o, psd, wavelength_nm))


def _direct(mu, above, psd, nano, wavelength_nm):
    """(A_R, A_T, tis_R, tis_T) of unpolarized light at one cosine *mu* from above (air) or from inside, on the nano
    interface *nano* (:mod:`waveoptics.brdf.nano_interface`)."""
    tis_r, tis_t = nano.tis(float(np.degrees(np.arccos(mu))), wavelength_nm, psd, "unpolarized", above)
    a_r, a_t = coherent_shares(nano.losses(mu, above, psd, wavelength_nm))
    return a_r, a_t, tis_r, tis_t


def _piece_nodes(piece):
    """The cosines of a piece's nodes: uniform in t, a kink's node moved into the piece by :data:`_KINK_OFFSET`
    (its own side's limit) and the grazing node at :data:`MU_GRAZING`."""
    lo, hi, k_lo, k_hi = piece
    mu = piece_cosine(np.linspace(0.0, 1.0, NANO_MU_NODES + 1), piece)
    if k_lo:
        mu[0] *= 1.0 + _KINK_OFFSET
    if k_hi:
        mu[-1] *= 1.0 - _KINK_OFFSET
    return np.maximum(mu, MU_GRAZING)


def check_perturbative(shares, mus, above: bool, psd: PSDModel, eta: float, wavelength_nm: float) -> None:
    """Refuse (a :class:`~waveoptics.errors.FieldError` naming ``psd``) nano-roughness beyond the perturbation
    theory of the nano-rough glass: where a coherent share A_R or A_T (*shares* (n, 2) at cosines *mus*) comes out
    negative, the second-order loss exceeds the light it is taken from (the series in the phase variance
    g = (4π σ n_i cos θ / λ)² has left its domain, g ≪ 1), and a negative coherent lobe would follow.

    References
    ----------
    .. [1] A. A. Maradudin, D. L. Mills, Phys. Rev. B 11(4), 1392–1415, 1975 (the second-order mean field, valid
       for small k σ).
    """
    bad = np.nonzero(np.min(shares, axis=1) < 0)[0]
    if bad.size == 0:
        return
    j = int(bad[np.argmin(np.min(shares[bad], axis=1))])
    n_i = 1.0 if above else float(eta)
    mu = float(mus[j])
    g = (4 * np.pi * psd.sigma * n_i * mu / (wavelength_nm * 1e-9)) ** 2
    side = "from the air" if above else "from inside the dielectric"
    raise FieldError(f"{{psd}} σ = {psd.sigma * 1e9:.3g} nm is beyond the nano-rough glass's perturbation theory at "
                     f"{wavelength_nm:g} nm: light {side} at θ = {np.degrees(np.arccos(mu)):.3g}° has phase "
                     f"variance g = (4πσ n cosθ/λ)² = {g:.2g}, where its second-order coherent share comes out "
                     f"{float(np.min(shares[j])):.3g} < 0; lower σ or the shortest wavelength", "psd")


def nano_tables(psd: PSDModel, eta, wavelength_nm: float) -> NanoTables:
    """The tables (:class:`NanoTables`) of air over a dielectric of real index *eta* (or the nano interface *eta*
    of :mod:`waveoptics.brdf.nano_interface`: bare or coated) with nano-roughness *psd* at *wavelength_nm* (nm): on
    each side, :data:`NANO_MU_NODES` + 1 nodes per piece of μ (split at the side's critical cosine between air and
    the dielectric; films do not move it), a not-a-knot cubic spline in the piece's variable t through them.

    References
    ----------
    .. [1] J. C. Stover 2012, §4.4 (TIS); Maradudin & Mills 1975, Johnson 1999 (the coherent split, SPM2).
    .. [2] C. de Boor, *A Practical Guide to Splines*, Springer 1978, ch. IV (the not-a-knot cubic spline).
    """
    nano = eta if hasattr(eta, "losses") else BareNano(float(eta))
    return _nano_tables(psd, nano, float(wavelength_nm))


@functools.lru_cache(maxsize=64)
def _nano_tables(psd: PSDModel, nano, wavelength_nm: float) -> NanoTables:
    eta = nano.eta
    t_nodes = np.linspace(0.0, 1.0, NANO_MU_NODES + 1)
    t = np.linspace(0.0, 1.0, NANO_DENSE_SAMPLES)
    mu_c = {True: critical_cosine(1.0, eta), False: critical_cosine(eta, 1.0)}
    values = {}
    for above in (True, False):
        rows = {name: [] for name in TABLE_NAMES}
        for piece in table_pieces(mu_c[above]):
            mus = _piece_nodes(piece)
            vals = np.array([_direct(m, above, psd, nano, wavelength_nm) for m in mus])
            check_perturbative(vals[:, :2], mus, above, psd, eta, wavelength_nm)
            for k, name in enumerate(TABLE_NAMES):
                rows[name].append(CubicSpline(t_nodes, vals[:, k])(t))
        values.update({(name, above): np.array(r) for name, r in rows.items()})
    return NanoTables(mu_c_up=mu_c[True], mu_c_down=mu_c[False], t=t, values=values)


@dataclass(frozen=True)
class NanoRoughDielectricBSDF(RoughDielectricBSDF):
    """Nano-rough glass (module doc): :class:`waveoptics.brdf.RoughDielectricBSDF` (take a small α) whose coherent
    lobes give up the first-order scatter of the nano-roughness *psd* (:class:`~waveoptics.surfaces.PSDModel`,
    m⁴), which :func:`waveoptics.scatter.rr_bsdf` spreads over both half-spaces.

    ``eval_parts`` adds ``nano`` (1/sr) and ``albedo_parts`` adds ``nano_reflection`` and ``nano_transmission``;
    ``sample`` draws the microfacet lobes with probability 1 − TIS(μ_i) and else a cosine-weighted direction on
    the reflection (TIS_R) or transmission (TIS_T) side.

    References
    ----------
    .. [1] Walter et al. 2007; Elson 1984; Stover 2012 (module references).
    """

    psd: PSDModel | None = None
    #: a thin-film stack on the glass: its interfaces rough (:class:`waveoptics.brdf.nano_interface.CoatedNano`)
    takes_stack: ClassVar[bool] = True

    def __post_init__(self):
        super().__post_init__()
        if self.psd is None or not hasattr(self.psd, "S") or not hasattr(self.psd, "sigma"):
            raise FieldError(f"{{psd}} must be a PSDModel (the nano-roughness), got {self.psd!r}", "psd")
        if not self.material.has_index:
            check_film_psd(self.psd)

    def _nano_interface(self, lam):
        """The nano interface at *lam* (nm): bare, or the material's films rough (:mod:`.nano_interface`)."""
        return nano_interface_of(self.material, float(lam))

    def _nano(self, lam) -> NanoTables:
        return nano_tables(self.psd, self._nano_interface(lam), float(lam))

    def _parts1(self, wi, wo, lam):
        fr, ft, mr, mt = super()._parts1(wi, wo, lam)
        tab = self._nano(lam)
        up, mu = wi[:, 2] > 0, np.abs(wi[:, 2])
        a_r, a_t = tab.at("A_R", mu, up), tab.at("A_T", mu, up)
        return fr * a_r, ft * a_t, mr * a_r, mt * a_t

    def _f_nano(self, wi, wo, lam):
        return self._nano_interface(lam).bsdf(wi, wo, lam, self.psd)

    def _eval1(self, wi, wo, lam):
        return sum(self._parts1(wi, wo, lam)) + self._f_nano(wi, wo, lam)

    def eval_parts(self, wi, wo, wavelength_nm) -> dict:
        """:meth:`RoughDielectricBSDF.eval_parts` (the coherent lobes, scaled) and ``nano`` (1/sr)."""
        out = super().eval_parts(wi, wo, wavelength_nm)
        wi_f, wo_f, lam, shape = broadcast_pair(wi, wo, wavelength_nm)
        nano = np.zeros(lam.size)
        for val in np.unique(lam):
            sel = lam == val
            nano[sel] = self._f_nano(wi_f[sel], wo_f[sel], float(val))
        out["nano"] = nano.reshape(shape)
        return out

    def _p_nano(self, wi, lam):
        """(TIS_R, TIS_T) at each ω_i: the probabilities of the nano lobes' samplers."""
        tab = self._nano(lam)
        up, mu = wi[:, 2] > 0, np.abs(wi[:, 2])
        return tab.at("tis_R", mu, up), tab.at("tis_T", mu, up)

    def _pdf1(self, wi, wo, lam):
        p_r, p_t = self._p_nano(wi, lam)
        same = (wi[:, 2] > 0) == (wo[:, 2] > 0)
        cos = np.abs(wo[:, 2]) / np.pi
        nano = np.where(wo[:, 2] != 0, np.where(same, p_r, p_t) * cos, 0.0)
        return (1.0 - p_r - p_t) * super()._pdf1(wi, wo, lam) + nano

    def _sample1(self, wi, u, lam):
        p_r, p_t = self._p_nano(wi, lam)
        idx, u[:, 0] = lobe_choice(u[:, 0], [1.0 - p_r - p_t, p_r, p_t])
        wo = super()._sample1(wi, u.copy(), lam)
        nano = idx > 0
        if np.any(nano):
            s = np.sign(wi[nano, 2]) * np.where(idx[nano] == 1, 1.0, -1.0)   # the side of the chosen lobe
            r = np.sqrt(u[nano, 0])
            phi = 2.0 * np.pi * u[nano, 1]
            z = np.sqrt(np.maximum(1.0 - u[nano, 0], 0.0)) * s
            wo[nano] = np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=-1)
        return wo

    def albedo_parts(self, wi, wavelength_nm) -> dict:
        """:meth:`RoughDielectricBSDF.albedo_parts` with the coherent factors, and ``nano_reflection``,
        ``nano_transmission`` (the TIS tables at μ_i; dimensionless)."""
        out = super().albedo_parts(wi, wavelength_nm)
        wi_f, lam_f, shape = broadcast_incidence(wi, wavelength_nm)
        extra = {k: np.zeros(lam_f.size) for k in ("A_R", "A_T", "nano_reflection", "nano_transmission")}
        for j, (w1, l1) in enumerate(zip(wi_f, lam_f)):
            tab = self._nano(float(l1))
            up, mu = w1[2] > 0, abs(w1[2])
            extra["A_R"][j], extra["A_T"][j] = tab.at("A_R", mu, up), tab.at("A_T", mu, up)
            extra["nano_reflection"][j] = tab.at("tis_R", mu, up)
            extra["nano_transmission"][j] = tab.at("tis_T", mu, up)
        a_r, a_t = extra["A_R"].reshape(shape), extra["A_T"].reshape(shape)
        out["reflection"] = out["reflection"] * a_r
        out["multiple_reflection"] = out["multiple_reflection"] * a_r
        out["transmission"] = out["transmission"] * a_t
        out["multiple_transmission"] = out["multiple_transmission"] * a_t
        out["nano_reflection"] = extra["nano_reflection"].reshape(shape)
        out["nano_transmission"] = extra["nano_transmission"].reshape(shape)
        return out
