"""First-order (Rayleigh-Rice / Elson) scatter from a thin-film stack whose interfaces are slightly rough, with
correlated, uncorrelated or partly correlated interface roughness (docs/physics.md §4 for one interface).

Model
-----
Interfaces are numbered from the substrate outwards: interface 0 lies between the substrate (ε_0 = n_sub²) and
film 0, interface N (N films) between the top film and the ambient (air, ε = 1); interface j separates
ε_below = ε_j from ε_above = ε_{j+1}. Interface j is displaced to z_j + h_j(x, y), h_j ≪ λ. To first order the
displacement is a sheet of induced dipoles: where h_j > 0 a slab of height h_j of the medium below replaces the
medium above. The surface dipole density that radiates, from the unperturbed (flat-stack) field E, D of the
incident wave at the interface, is the boundary-perturbation form (tangential E and normal D are continuous there,
so it does not depend on which side they are taken)

    p_j(x, y) = ε₀ h_j(x, y) [ (ε_below − ε_above) E_t + (1/ε_above − 1/ε_below) D_z ẑ / ε₀ ]

(the first-order perturbation of a displaced boundary, Δε E_∥ − Δ(ε⁻¹) D_⊥, Johnson et al. 2002; Elson's
theory of rough stacks, 1976–1984, is this first order in h). By reciprocity, the far field that a dipole p at
depth z in the stack radiates into the ambient along ω_o with polarization ê_b is (k²/4πε₀) (e^{ikr}/r)
p · E'_b(z), where E'_b is the total field of the flat stack when a unit plane wave of polarization ê_b comes in
from ω_o (Lorentz reciprocity; Sipe 1987). Integrating over the sheet gives the Fourier transform of h_j at the
Bragg frequency f = (ω_i + ω_o)_xy / λ, and with ⟨H_j H_k*⟩ = A S_jk(f):

    f_ab(ω_i, ω_o) = k⁴ / (16 π² cosθ_i cosθ_o) Σ_j Σ_k G_j^{ab} G_k^{ab*} S_jk(f),
    G_j^{ab} = (ε_below − ε_above) [ E_t^a · E'_t^b + D_z^a D'_z^b / (ε_above ε_below) ]          (1)

with E^a the flat-stack field of a unit incident wave of polarization a (s, p) at interface j and D_z its normal
displacement over ε₀. S_jj is the PSD of interface j; for identical profiles replicated through the stack
(correlated roughness) S_jk = S, for independent ones S_jk = 0 (j ≠ k), and a cross-correlation coefficient c_jk
gives S_jk = c_jk √(S_j S_k) (Elson, Rahn & Bennett 1983). For one interface (a bare substrate, ε_below = ε,
ε_above = 1) the fields are Fresnel's and (1) is exactly the Rayleigh-Rice BRDF (16π²/λ⁴) cosθ_i cosθ_o |q_ab|² S
with Germer's q factors (:func:`waveoptics.scatter.q_factors`): q_ab = G^{ab} / (4 cosθ_i cosθ_o) up to a
phase.
Two conformal interfaces with a film of zero thickness add to that one interface:
(ε_s − ε_f)[…/ε_f ε_s] + (ε_f − 1)[…/ε_f] = (ε_s − 1)[E_t·E'_t + D_z D'_z/ε_s].

Fields in the stack
-------------------
Each wave is carried by its plane of incidence (lateral unit vector û along its lateral wave vector k₀κ,
ŝ = ẑ × û) and two quantities continuous at every interface, propagated with Abelès' characteristic matrix of
each film (Born & Wolf §1.6.2; Macleod §2.2): for s, U = E_y (along ŝ) and V = (1/ik₀) ∂_z E_y; for p, U = H_y
(along ŝ, in units of the ambient's wave impedance) and V = (1/ik₀ε) ∂_z H_y, for which E_t = V û and
D_z/ε₀ = −κ U. In a film of index n_j with q_j = √(ε_j − κ²) (Im q_j ≥ 0), thickness d_j, β_j = k₀ q_j d_j and
η_j = q_j (s) or q_j/ε_j (p):

    (U, V)(z + d_j) = [[cos β_j, i sin β_j / η_j], [i η_j sin β_j, cos β_j]] (U, V)(z).

Starting from the substrate's transmitted wave (U, V) = (1, −η_sub) at interface 0 and carrying it up to the
ambient, the incident amplitude there is A = (U − V/η_0)/2; every interface field is divided by A (unit incident
wave). A wave coming from the substrate is the mirror image z → −z of the reversed stack lit from above (E_t kept,
D_z of opposite sign; for p, U = n E in a medium of index n), :mod:`waveoptics.scatter.rough_film_sides`.
Numerical range: the upward product grows as e^{Σ Im β_j}, harmless for films below a few µm of metal (e^{709}
overflows).

Where it holds: the smooth-surface limit, (4π σ_j cosθ / λ)² ≪ 1 at every interface and slopes ≪ 1, as for one
interface. Only the reflection hemisphere is evaluated here (light scattered into a transparent substrate, and light
from inside it: :mod:`waveoptics.scatter.rough_film_sides`; into guided modes of the films, Elson 1995: not), the
ambient is air, and each profile's PSD is taken at the same Bragg frequency (interfaces are laterally stationary).
No equation numbers of Elson's papers are quoted: eq. (1) was derived here and is checked against Germer's
single-interface q factors and the limits in tests/test_rough_film.py.

References
----------
.. [1] J. M. Elson, "Light scattering from surfaces with a single dielectric overlayer", J. Opt. Soc. Am. 66(7),
   682–694, 1976.
.. [2] J. M. Elson, "Infrared light scattering from surfaces covered with multiple dielectric overlayers",
   Appl. Opt. 16(11), 2872–2881, 1977.
.. [3] J. M. Elson, J. M. Bennett, "Vector scattering theory", Opt. Eng. 18(2), 116–124, 1979.
.. [4] J. M. Elson, J. P. Rahn, J. M. Bennett, "Relationship of the total integrated scattering from
   multilayer-coated optics to angle of incidence, polarization, correlation length, and roughness
   cross-correlation properties", Appl. Opt. 22(20), 3207–3219, 1983.
.. [5] J. M. Elson, "Theory of light scattering from a rough surface with an inhomogeneous dielectric
   permittivity", Phys. Rev. B 30(10), 5460–5480, 1984.
.. [6] J. M. Elson, "Multilayer-coated optics: guided-wave coupling and scattering by means of interface random
   roughness", J. Opt. Soc. Am. A 12(4), 729–742, 1995; and "Theory and software for light scattering from
   multilayer optical components with interfacial roughness", NAWCWPNS TP 8084, 1992.
.. [7] S. G. Johnson, M. Ibanescu, M. A. Skorobogatiy, O. Weisberg, J. D. Joannopoulos, Y. Fink, "Perturbation
   theory for Maxwell's equations with shifting material boundaries", Phys. Rev. E 65, 066611, 2002.
.. [8] J. E. Sipe, "New Green-function formalism for surface optics", J. Opt. Soc. Am. B 4(4), 481–489, 1987.
.. [9] T. A. Germer, SCATMECH (NIST): Roughness_Stack_BRDF_Model, Correlated_ and Uncorrelated_Roughness_Stack_
   BRDF_Model documentation (single rough interface of a stack after Elson; all interfaces correlated or not).
.. [10] M. Born, E. Wolf, *Principles of Optics*, 7th ed., Cambridge 1999, §1.6.2 (characteristic matrix).
.. [11] J. C. Stover, *Optical Scattering: Measurement and Analysis*, 3rd ed., SPIE 2012, eq. (4.1) (the
   Rayleigh-Rice BRDF of one interface).
"""
from __future__ import annotations

import numpy as np

from ..errors import FieldError, unknown
from ..vocabulary import POLARIZATIONS, ROUGHNESS_CORRELATIONS
from .polar import polar_albedo

__all__ = ["CORRELATIONS", "stack_layers", "interface_fields", "direction_fields", "interface_amplitudes",
           "bragg_psd", "cross_psd_weights", "interface_psd_list", "interface_spectra", "cross_psd_pairs",
           "correlated_sum",
           "rough_stack_components", "rough_stack_brdf", "rough_stack_tis"]

#: named interface-roughness correlations: identical replicated profiles, or independent ones
CORRELATIONS = ROUGHNESS_CORRELATIONS


def stack_layers(stack_or_layers, wavelength_nm):
    """(ε of the media from the substrate up to the ambient, film thicknesses in nm) of a stack.

    *stack_or_layers*: a :class:`~waveoptics.materials.Stack`, a bare material (has ``eta``), or a tuple
    ``(n_substrate, n_films, d_films_nm)`` with the films from the substrate outwards (complex indices n + ik).
    """
    w = np.asarray(wavelength_nm, dtype=float)
    if hasattr(stack_or_layers, "films") and hasattr(stack_or_layers, "substrate"):
        ns, nf = stack_or_layers.indices(w)
        d = list(stack_or_layers.thicknesses_nm)
    elif hasattr(stack_or_layers, "eta"):
        ns, nf, d = stack_or_layers.eta(w), [], []
    else:
        try:
            ns, nf, d = stack_or_layers
        except (TypeError, ValueError):
            raise FieldError("{stack} must be a Stack, a material or (n_substrate, n_films, d_films_nm); got "
                             f"{stack_or_layers!r}", "stack") from None
        nf, d = list(nf), [float(x) for x in d]
    if len(nf) != len(d):
        raise FieldError(f"{{stack}}: {len(nf)} film indices but {len(d)} thicknesses", "stack")
    if any(not np.isfinite(x) or x < 0 for x in d):
        raise FieldError(f"{{stack}}: film thicknesses {d!r} nm must be finite and >= 0", "stack")
    eps = [np.asarray(n, dtype=np.complex128) ** 2 for n in (ns, *nf)] + [np.complex128(1.0)]
    return eps, d


def _qz(eps, kappa2):
    """q = √(ε − κ²) on the branch Im q ≥ 0 (decaying downwards into an absorbing or evanescent medium)."""
    q = np.sqrt(eps - kappa2)
    # guard: a rounding −0.0 imaginary part would put an evanescent q on the growing branch
    if np.ndim(q) == 0:
        return -q if q.imag < 0 else q
    return np.negative(q, out=q, where=q.imag < 0)


def _fields_sp(kappa, wavelength_nm, eps, d_nm, from_above: bool = True, cos_theta=None):
    """The fields of :func:`interface_fields` for both polarizations in one pass (the normal wave numbers q_j and
    each film's phase cos β_j, i sin β_j shared by s and p): lists over interfaces (substrate first) of E_t of s,
    E_t of p and D_z/ε₀ of p (that of s is 0).

    References
    ----------
    .. [1] M. Born, E. Wolf, *Principles of Optics*, 7th ed., §1.6.2 (characteristic matrix of a film).
    """
    if not from_above:
        es, ep, dp = _fields_sp(kappa, wavelength_nm, eps[::-1], d_nm[::-1], True, cos_theta)
        return es[::-1], ep[::-1], [-x for x in dp[::-1]]
    kappa = np.asarray(kappa, dtype=float)
    k2 = kappa ** 2
    k0 = 2.0 * np.pi / np.asarray(wavelength_nm, dtype=float)        # 1/nm
    top = len(eps) - 1
    if cos_theta is None:
        q = [_qz(e, k2) for e in eps]
    else:                                               # the incidence medium is transparent (a real index)
        q = [_qz(e, k2) for e in eps[:-1]] + [np.sqrt(eps[-1]) * np.abs(np.asarray(cos_theta, dtype=float))]
    etas = (q, [qj / e for qj, e in zip(q, eps)])       # η_j of s and of p
    ones = np.ones(np.broadcast(k2, *eps).shape, dtype=np.complex128)
    waves = tuple([(ones, -eta[0] * ones)] for eta in etas)
    for j, d in enumerate(d_nm, start=1):               # film j sits on interface j−1, under interface j
        b = k0 * q[j] * d
        c, i_s = np.cos(b), 1j * np.sin(b)
        for eta, at in zip(etas, waves):
            U, V = at[-1]
            at.append((c * U + i_s / eta[j] * V, eta[j] * i_s * U + c * V))
    # guard: at grazing incidence (q_0 = 0) the incident and reflected waves cancel (r = −1, the limit that
    # :func:`waveoptics.materials.stack.amplitudes` takes): every interface field is 0 there, not 0/0
    grazing = k2 >= np.real(eps[-1])
    inv = []
    for eta, at in zip(etas, waves):
        U, V = at[-1]
        with np.errstate(divide="ignore", invalid="ignore"):
            A = 0.5 * (U - V / eta[top])                 # incident amplitude of U in the incidence medium
            inv.append(np.where(grazing, 0.0, 1.0 / np.where(grazing, 1.0, A)))
    inv_p = inv[1] * np.sqrt(eps[-1])                   # unit E: U = n E in the incidence medium (n = 1 in air)
    return ([u * inv[0] for u, _ in waves[0]], [v * inv_p for _, v in waves[1]],
            [-kappa * u * inv_p for u, _ in waves[1]])


def interface_fields(kappa, wavelength_nm, eps, d_nm, polarization: str, from_above: bool = True, cos_theta=None):
    """Flat-stack fields at every interface for a plane wave of unit electric amplitude with lateral index
    *kappa* (κ = n sinθ in its medium) coming from the ambient (*from_above*) or from the substrate (which must
    then be transparent): a list, interface 0 (substrate) first, of (E_t, D_z) where E_t is the tangential field
    along ŝ (s) or û (p) and D_z the normal displacement over ε₀ (0 for s). See the module docstring.

    From the substrate the fields are the mirror image (z → −z) of the reversed stack lit from above: E_t is kept
    and D_z changes sign; the wave's amplitude is normalized in its own medium (for p, U = Z₀H_y = n E).
    *cos_theta*, when given, is the wave's |cosθ| in its medium: its normal wave number there is n |cosθ| rather
    than √(n² − κ²), which loses digits near grazing incidence.

    References
    ----------
    .. [1] M. Born, E. Wolf, *Principles of Optics*, 7th ed., §1.6.2 (characteristic matrix of a film).
    .. [2] H. A. Macleod, *Thin-Film Optical Filters*, 4th ed., CRC Press 2010, §2.2.
    """
    es, ep, dp = _fields_sp(kappa, wavelength_nm, eps, d_nm, from_above, cos_theta)
    if polarization == "s":
        return [(e, np.zeros_like(e)) for e in es]
    return list(zip(ep, dp))


def _direction_fields_sp(w, wavelength_nm, eps, d_nm):
    """:func:`_fields_sp` of the unit wave that comes in from the direction *w* (..., 3; towards its source), each
    side computed on its own directions only."""
    w = np.asarray(w, dtype=float)
    s = np.hypot(w[..., 0], w[..., 1])
    up = w[..., 2] >= 0
    n_s = np.sqrt(eps[0]).real
    if np.all(up) or not np.any(up):
        side = bool(np.all(up))
        return _fields_sp(s if side else n_s * s, wavelength_nm, eps, d_nm, side, w[..., 2])
    shape = np.broadcast_shapes(up.shape, np.shape(wavelength_nm), *(np.shape(e) for e in eps))
    up = np.broadcast_to(up, shape).reshape(-1)
    out = tuple([np.empty(up.size, dtype=np.complex128) for _ in range(len(eps) - 1)] for _ in range(3))
    for side, idx in ((True, np.flatnonzero(up)), (False, np.flatnonzero(~up))):
        s_m, n_m, z_m, lam_m, *eps_m = [x if np.ndim(x) == 0 else np.broadcast_to(x, shape).reshape(-1)[idx]
                                        for x in (s, n_s, w[..., 2], wavelength_nm, *eps)]
        for dst, src in zip(out, _fields_sp(s_m if side else n_m * s_m, lam_m, eps_m, d_nm, side, z_m)):
            for x, y in zip(dst, src):
                x[idx] = y
    return tuple([x.reshape(shape) for x in part] for part in out)


def _wave_fields(w, wavelength_nm, eps, d_nm):
    """:func:`_direction_fields_sp` of the directions *w* (..., n, 3), computed once a row where every direction
    of each row (along the axis n) has the same w_z and, to rounding (4 ulp), the same |w_xy| (a grid of
    azimuths at each polar angle, as :func:`~waveoptics.scatter.transmission.hemisphere_albedo`'s): the fields
    depend on a direction through these two only, so a row's first direction stands for it (arrays (..., 1))."""
    w = np.asarray(w, dtype=float)
    if w.ndim >= 3 and w.shape[-2] > 1 and np.ndim(wavelength_nm) == 0 and all(np.ndim(e) == 0 for e in eps):
        z = w[..., 2]
        if np.all(z == z[..., :1]):
            s = np.hypot(w[..., 0], w[..., 1])
            if np.all(np.abs(s - s[..., :1]) <= 8.9e-16 * s[..., :1]):
                return _direction_fields_sp(w[..., :1, :], wavelength_nm, eps, d_nm)
    return _direction_fields_sp(w, wavelength_nm, eps, d_nm)


def direction_fields(w, wavelength_nm, eps, d_nm, polarization: str):
    """:func:`interface_fields` of the unit wave that comes in from the direction *w* (..., 3; towards its source):
    from the ambient where w_z ≥ 0, from the substrate (lateral index n_sub sinθ) where w_z < 0."""
    es, ep, dp = _direction_fields_sp(w, wavelength_nm, eps, d_nm)
    if polarization == "s":
        return [(e, np.zeros_like(e)) for e in es]
    return list(zip(ep, dp))


def _planes(wi, wo):
    """Lateral unit vectors (û_i, û_o), each (..., 2), of the incident wave (travelling along −ω_i) and of the
    reciprocal wave (travelling along −ω_o), with the planes of :func:`scattering_angles` at normal incidence (x–z)
    and normal exit (φ_s = 0); ŝ = ẑ × û."""
    wi, wo = np.asarray(wi, dtype=float), np.asarray(wo, dtype=float)
    si = np.hypot(wi[..., 0], wi[..., 1])
    so = np.hypot(wo[..., 0], wo[..., 1])
    # guard: undefined azimuths take the x axis (incidence) and the specular side (exit)
    e = np.stack([np.where(si > 0, wi[..., 0] / np.where(si > 0, si, 1.0), 1.0),
                  np.where(si > 0, wi[..., 1] / np.where(si > 0, si, 1.0), 0.0)], axis=-1)
    o = np.stack([np.where(so > 0, wo[..., 0] / np.where(so > 0, so, 1.0), -e[..., 0]),
                  np.where(so > 0, wo[..., 1] / np.where(so > 0, so, 1.0), -e[..., 1])], axis=-1)
    return -e, -o


def interface_amplitudes(wi, wo, wavelength_nm, eps, d_nm) -> dict:
    """G_j^{ab} of eq. (1) of the module docstring for ab in ss, sp, ps, pp: a dict of lists over interfaces
    (substrate first), each an array of the directions' shape (unitless). Each wave comes in from its direction's
    side (:func:`direction_fields`: from the substrate where w_z < 0) with unit electric amplitude; the D_z term
    enters pp only (D_z of s is 0)."""
    ui, uo = _planes(wi, wo)
    es_i, ep_i, dp_i = _wave_fields(wi, wavelength_nm, eps, d_nm)
    es_o, ep_o, dp_o = _wave_fields(wo, wavelength_nm, eps, d_nm)
    # ŝ = ẑ × û: ŝ_i·ŝ_o = û_i·û_o and ŝ_i·û_o = −û_i·ŝ_o = (û_i × û_o)_z
    cos_io = ui[..., 0] * uo[..., 0] + ui[..., 1] * uo[..., 1]
    sin_io = ui[..., 0] * uo[..., 1] - ui[..., 1] * uo[..., 0]
    out = {ab: [] for ab in ("ss", "sp", "ps", "pp")}
    for j in range(len(eps) - 1):
        below, above = eps[j], eps[j + 1]
        jump = below - above                            # the fields' factors first: a wave's may be one a row
        out["ss"].append(jump * es_i[j] * es_o[j] * cos_io)
        out["sp"].append(jump * es_i[j] * ep_o[j] * sin_io)
        out["ps"].append(-(jump * ep_i[j] * es_o[j]) * sin_io)
        out["pp"].append(jump * ep_i[j] * ep_o[j] * cos_io + jump / (above * below) * dp_i[j] * dp_o[j])
    return out


def bragg_psd(model, wi, wo, wavelength_nm, n_i=1.0, n_o=1.0):
    """S(f) (m⁴) of one interface at the Bragg frequency f = (n_i ω_i + n_o ω_o)_xy / λ (1/m; n_i, n_o the indices
    of the media of ω_i and ω_o, the grating equation); 0 for a smooth one (None)."""
    n_i, n_o = np.asarray(n_i, dtype=float)[..., None], np.asarray(n_o, dtype=float)[..., None]
    s = n_i * np.asarray(wi, dtype=float) + n_o * np.asarray(wo, dtype=float)
    lam = np.asarray(wavelength_nm, dtype=float) * 1e-9
    if model is None:
        return np.zeros(np.broadcast(s[..., 0], lam).shape)
    if hasattr(model, "S_xy"):
        return model.S_xy(s[..., 0] / lam, s[..., 1] / lam)
    return model.S(np.hypot(s[..., 0], s[..., 1]) / lam)


def cross_psd_weights(correlation, n: int) -> np.ndarray:
    """The n × n cross-correlation coefficients c_jk of the interfaces (S_jk = c_jk √(S_j S_k)): 1 everywhere for
    ``"correlated"``, the identity for ``"uncorrelated"``, c off the diagonal for a number c in [0, 1], or a
    symmetric n × n array with a unit diagonal.

    References
    ----------
    .. [1] J. M. Elson, J. P. Rahn, J. M. Bennett, Appl. Opt. 22(20), 3207–3219, 1983 (partly correlated
       interfaces).
    """
    if isinstance(correlation, str):
        if correlation not in CORRELATIONS:
            raise unknown("correlation", correlation, CORRELATIONS, field="correlation")
        return np.ones((n, n)) if correlation == "correlated" else np.eye(n)
    c = np.asarray(correlation, dtype=float)
    if c.ndim == 0:
        if not 0.0 <= float(c) <= 1.0:
            raise FieldError(f"{{correlation}} {float(c)!r} is not allowed; a coefficient must lie in [0, 1]",
                             "correlation")
        return np.where(np.eye(n, dtype=bool), 1.0, float(c))
    if c.shape != (n, n) or not np.allclose(c, c.T) or not np.allclose(np.diag(c), 1.0) or np.any(np.abs(c) > 1):
        raise FieldError(f"{{correlation}} must be a symmetric {n}x{n} array with a unit diagonal and |c| <= 1; "
                         f"got shape {c.shape}", "correlation")
    return c


def interface_psd_list(interface_psds, n: int) -> list:
    """The PSD model (or None, smooth) of each of the *n* interfaces, substrate first: one model or None stands
    for every interface."""
    if interface_psds is None or hasattr(interface_psds, "S") or hasattr(interface_psds, "S_xy"):
        return [interface_psds] * n
    psds = list(interface_psds)
    if len(psds) != n:
        raise FieldError(f"{{interface_psds}}: {len(psds)} PSDs for a stack of {n} interfaces (one per interface, "
                         "substrate first; None for a smooth one)", "interface_psds")
    return psds


def interface_spectra(wi, wo, wavelength_nm, stack_or_layers, interface_psds, n: int, n_i=1.0, n_o=1.0) -> list:
    """S_j(f) (m⁴) of each of the *n* interfaces at the Bragg frequency of :func:`bragg_psd`, a
    :class:`~waveoptics.materials.Stack`'s ``interface_roughness`` r_j scaling interface j's PSD by r_j² (a model
    shared by several interfaces is evaluated once)."""
    r = getattr(stack_or_layers, "roughness_scales", (1.0,) * n)
    models = interface_psd_list(interface_psds, n)
    S = {}
    for m in models:
        if id(m) not in S:
            S[id(m)] = bragg_psd(m, wi, wo, wavelength_nm, n_i, n_o)
    return [r_j * r_j * S[id(m)] for m, r_j in zip(models, r)]


def cross_psd_pairs(S: list, c) -> list:
    """(j, k, w_jk) of the nonzero terms of Σ_j Σ_k c_jk √(S_j S_k) Re(G_j G_k*) taken once a pair (j ≤ k; c is
    symmetric): w_jj = c_jj S_j and w_jk = 2 c_jk √(S_j S_k) (m⁴), for :func:`correlated_sum`.

    References
    ----------
    .. [1] J. M. Elson, J. P. Rahn, J. M. Bennett, Appl. Opt. 22(20), 3207–3219, 1983 (partly correlated
       interfaces: S_jk = c_jk √(S_j S_k)).
    """
    pairs = []
    for j in range(len(S)):
        if c[j, j] != 0.0:
            pairs.append((j, j, c[j, j] * S[j]))
        for k in range(j + 1, len(S)):
            if c[j, k] != 0.0:
                pairs.append((j, k, 2.0 * c[j, k] * np.sqrt(S[j] * S[k])))
    return pairs


def correlated_sum(G: list, S: list, c, pairs=None) -> np.ndarray:
    """Σ_j Σ_k c_jk √(S_j S_k) Re(G_j G_k*) of eq. (1) (m⁴): the interfaces' amplitudes *G* weighted by their
    cross-PSDs (:func:`cross_psd_weights` *c*); *pairs*, when given, the weights of :func:`cross_psd_pairs`."""
    total = 0.0
    for j, k, w in cross_psd_pairs(S, c) if pairs is None else pairs:
        g, h = G[j], G[k]
        total = total + w * (g.real * h.real + g.imag * h.imag)
    return total


def rough_stack_components(wi, wo, wavelength_nm, stack_or_layers, interface_psds,
                           correlation="correlated") -> dict:
    """The four polarized BRDFs f_ss, f_sp, f_ps, f_pp (1/sr; first index incident, second scattered) of eq. (1)
    of the module docstring; 0 below the horizon."""
    eps, d = stack_layers(stack_or_layers, wavelength_nm)
    n = len(eps) - 1
    S = interface_spectra(wi, wo, wavelength_nm, stack_or_layers, interface_psds, n)
    c = cross_psd_weights(correlation, n)
    G = interface_amplitudes(wi, wo, wavelength_nm, eps, d)
    ci, co = np.asarray(wi, dtype=float)[..., 2], np.asarray(wo, dtype=float)[..., 2]
    ok = (ci > 0) & (co > 0)
    k = 2.0 * np.pi / (np.asarray(wavelength_nm, dtype=float) * 1e-9)
    pre = k ** 4 / (16.0 * np.pi ** 2 * np.where(ok, ci * co, 1.0))
    pairs = cross_psd_pairs(S, c)
    return {ab: np.where(ok, pre * correlated_sum(Gab, S, c, pairs), 0.0) for ab, Gab in G.items()}


def rough_stack_brdf(wi, wo, wavelength_nm, stack_or_layers, interface_psds, correlation="correlated",
                     polarization_in: str = "unpolarized", polarization_out: str | None = None):
    """First-order BRDF (1/sr) of a thin-film stack with rough interfaces (Elson; module docstring eq. (1)).

    Parameters
    ----------
    wi, wo : array_like (..., 3)
        Unit vectors towards the light and the viewer (macro normal +z; air above the stack).
    wavelength_nm : array_like, nm
        Vacuum wavelength (broadcast against the directions).
    stack_or_layers : Stack, Material or (n_substrate, n_films, d_films_nm)
        The stack: films from the substrate outwards, thicknesses in nm (:func:`stack_layers`). A
        :class:`~waveoptics.materials.Stack` with ``interface_roughness`` r_j scales interface j's PSD by r_j².
    interface_psds : PSDModel, PeriodogramPSD, None or sequence of them
        Height PSD of each interface (m⁴ at f in 1/m), substrate interface first, the top (air) interface last;
        one model stands for every interface, None for a smooth one.
    correlation : {'correlated', 'uncorrelated'}, float or (n, n) array
        Cross-correlation of the interfaces' profiles: S_jk = c_jk √(S_j S_k) (:func:`cross_psd_weights`).
    polarization_in : {'unpolarized', 's', 'p'}
        Incident polarization ('unpolarized': the mean of s and p).
    polarization_out : {None, 's', 'p'}
        Analyzed scattered polarization (None: not analyzed, the sum of s and p).

    References
    ----------
    .. [1] J. M. Elson, Appl. Opt. 16(11), 2872–2881, 1977; Phys. Rev. B 30(10), 5460–5480, 1984.
    .. [2] J. M. Elson, J. P. Rahn, J. M. Bennett, Appl. Opt. 22(20), 3207–3219, 1983.
    .. [3] S. G. Johnson et al., Phys. Rev. E 65, 066611, 2002 (the boundary-perturbation dipole sheet).
    """
    if polarization_in not in POLARIZATIONS:
        raise unknown("polarization", polarization_in, POLARIZATIONS, field="polarization_in")
    if polarization_out not in (None, "s", "p"):
        raise unknown("polarization", polarization_out, ("s", "p"), field="polarization_out")
    f = rough_stack_components(wi, wo, wavelength_nm, stack_or_layers, interface_psds, correlation)
    outs = ("s", "p") if polarization_out is None else (polarization_out,)
    ins = ("s", "p") if polarization_in == "unpolarized" else (polarization_in,)
    total = sum(f[a + b] for a in ins for b in outs)
    return total / len(ins)


def rough_stack_tis(theta_deg, wavelength_nm, stack_or_layers, interface_psds, correlation="correlated",
                    polarization: str = "unpolarized") -> float:
    """Total integrated scatter ∫ f cosθ_o dω_o (unitless, a share of the incident power) of the rough stack
    into the reflection hemisphere at incidence *theta_deg* (deg), by the polar quadrature of
    :func:`waveoptics.scatter.polar_albedo`.

    References
    ----------
    .. [1] J. M. Elson, J. P. Rahn, J. M. Bennett, Appl. Opt. 22(20), 3207–3219, 1983 (TIS of multilayers).
    """
    lam = float(wavelength_nm)
    t = np.radians(float(theta_deg))
    k = 2.0 * np.pi / (lam * 1e-9)
    eps, _ = stack_layers(stack_or_layers, lam)
    psds = [m for m in interface_psd_list(interface_psds, len(eps) - 1) if m is not None]
    if not psds:
        return 0.0
    scale = min(m.length_scale for m in psds)

    def lobe(wi_b, wo, q):
        return rough_stack_brdf(wi_b, wo, lam, stack_or_layers, interface_psds, correlation, polarization)

    return polar_albedo(float(t), k, scale, lobe)
