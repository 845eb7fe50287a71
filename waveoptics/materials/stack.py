"""Reflection and transmission of a stack of thin films on a substrate: the recursive Airy (Rouard) form of the
transfer-matrix (Abelès) method, for any number of layers, absorbing media included.

Geometry and conventions
------------------------
Light comes from a non-absorbing incident medium of index ``n_incident`` (air: 1) at cos θ_i. The films are listed
**from the substrate outwards**: ``n_films[0]`` lies on the substrate, ``n_films[-1]`` faces the incident medium
(the order of the material grammar ``"Al|Al2O3:120nm"``, :func:`waveoptics.materials.get_material`). Indices are
n + ik with k ≥ 0 (the exp(−iωt) convention of refractiveindex.info, as :mod:`waveoptics.materials.fresnel`);
thicknesses are in nm, wavelengths in vacuum in nm. Every argument broadcasts: cos θ_i against the wavelengths and
against each index (an index may be a spectrum of the wavelengths' shape).

In each medium j the normal component of the wave vector is k₀ q_j with q_j = n_j cos θ_j = √(n_j² − n₀² sin²θ_i)
(Snell's law as the conservation of n sin θ). The branch is the one with Im q_j ≥ 0 (then Re q_j ≥ 0 too, as
Im n_j² ≥ 0): the wave decays away from the interface into an absorbing layer, and is the decaying evanescent wave
beyond a critical angle. The interface coefficients, from medium a into medium b, are

    s:  r_ab = (q_a − q_b)/(q_a + q_b),                        t_ab = 2 q_a/(q_a + q_b)
    p:  r_ab = (n_b² q_a − n_a² q_b)/(n_b² q_a + n_a² q_b),    t_ab = 2 n_a n_b q_a/(n_b² q_a + n_a² q_b)

(the p convention of :func:`waveoptics.materials.fresnel.F_sp`; t_p is the ratio of the electric field amplitudes,
Born & Wolf's t_∥). They obey r_ba = −r_ab and t_ab t_ba = 1 − r_ab², which makes the multiple-beam (Airy) sum of
one film exact. Starting from the substrate interface, each film j of thickness d_j with phase thickness
β_j = k₀ q_j d_j is added by

    r ← (r_uj + r e^{2iβ_j}) / (1 + r_uj r e^{2iβ_j}),    t ← t_uj t e^{iβ_j} / (1 + r_uj r e^{2iβ_j}),

u being the medium above film j (Rouard's recurrence; the same 2×2 products as Abelès' characteristic matrices,
Heavens 1955 §4.3, Macleod §2.6). Numerical stability: with Im q_j ≥ 0 and d_j ≥ 0, |e^{iβ_j}| ≤ 1, so nothing
grows: a thick absorbing layer makes e^{2iβ_j} underflow to 0 and leaves the interface value, where the product
of characteristic matrices would overflow (its cosh, sinh grow as e^{|Im β|}).

Power coefficients (the normal Poynting flux, Born & Wolf §1.5.3): R = |r|², T_s = Re(q_sub)/q₀ |t_s|²,
T_p = Re(q_sub n_sub*/n_sub)/q₀ |t_p|²; T is the flux that enters the substrate (all absorbed there when it
absorbs), and A = 1 − R − T the share absorbed in the films (0 for lossless films: R and T are computed from r
and t separately, so R + T = 1 is a check, not an identity).

At grazing incidence (cos θ_i = 0) every stack reflects totally: r = −1, t = 0 (the limit, taken explicitly
because the interface formulas are 0/0 there when a film's index equals the incident medium's).

References
----------
.. [1] F. Abelès, "Recherches sur la propagation des ondes électromagnétiques sinusoïdales dans les milieux
   stratifiés. Application aux couches minces", Ann. Phys. (Paris) 12(5), 596–640 and 706–782, 1950.
.. [2] M. Born, E. Wolf, *Principles of Optics*, 7th ed., Cambridge 1999, §1.5 (Fresnel formulae, energy flux),
   §1.6 (stratified media, characteristic matrix, §1.6.4 the single film's Airy formula), §14.4 (absorbing films).
.. [3] O. S. Heavens, *Optical Properties of Thin Solid Films*, Butterworths 1955 (Dover 1991), ch. 4
   (multiple films, Rouard's method, absorbing films).
.. [4] H. A. Macleod, *Thin-Film Optical Filters*, 4th ed., CRC Press 2010, ch. 2 (characteristic matrix,
   admittances, potential transmittance and absorptance), ch. 4 (quarter-wave antireflection), ch. 6
   (quarter-wave mirrors).
"""
from __future__ import annotations

import numpy as np

from ..errors import WaveopticsError

__all__ = ['POLARIZATIONS', 'amplitudes', 'r_s', 'r_p', 't_s', 't_p', 'R', 'T', 'A']

#: the polarizations of :func:`amplitudes`; :func:`R`, :func:`T`, :func:`A` also take ``"unpolarized"``
POLARIZATIONS = ("s", "p")


def _index(n, what: str) -> np.ndarray:
    e = np.asarray(n, dtype=np.complex128)
    if not np.all(np.isfinite(e)) or np.any(e.real <= 0) or np.any(e.imag < 0):
        bad = e.ravel()[~(np.isfinite(e) & (e.real > 0) & (e.imag >= 0)).ravel()][0]
        raise WaveopticsError(f"{what} index {bad!r} is not allowed; it must be finite with n > 0 and k >= 0 "
                              "(n + ik)")
    return e


def _q(n, s2) -> np.ndarray:
    """n cos θ = √(n² − n₀² sin²θ_i) on the branch Im ≥ 0 (decaying into the medium)."""
    q = np.sqrt(n * n - s2)
    # guard: a rounding −0.0 imaginary part puts an evanescent q on the growing branch; flip it to Im ≥ 0
    return np.where(q.imag < 0, -q, q)


def _interface(pol: str, na, qa, nb, qb):
    """(r_ab, t_ab) from medium a into medium b (module docstring)."""
    if pol == "s":
        den = qa + qb
        return (qa - qb) / den, 2.0 * qa / den
    den = nb * nb * qa + na * na * qb
    return (nb * nb * qa - na * na * qb) / den, 2.0 * na * nb * qa / den


def _check(cos_theta_i, wavelength_nm, n_substrate, n_films, d_films_nm, n_incident, polarization):
    if polarization not in POLARIZATIONS:
        raise WaveopticsError(f"polarization {polarization!r} is not allowed; use s or p")
    n_films = list(n_films)
    d = [float(x) for x in d_films_nm]
    if len(d) != len(n_films):
        raise WaveopticsError(f"{len(n_films)} film indices but {len(d)} thicknesses; give one thickness per film")
    if any(not np.isfinite(x) or x < 0 for x in d):
        raise WaveopticsError(f"film thicknesses {d!r} nm are not allowed; each must be finite and >= 0")
    n0 = np.asarray(n_incident, dtype=np.complex128)
    if np.any(n0.imag != 0) or np.any(n0.real <= 0):
        raise WaveopticsError(f"incident medium index {n_incident!r} is not allowed; it must be real and > 0 "
                              "(a non-absorbing medium)")
    lam = np.asarray(wavelength_nm, dtype=np.float64)
    if not np.all(np.isfinite(lam) & (lam > 0)):
        raise WaveopticsError("wavelengths must be finite and > 0 nm")
    # guard: clamp cos θ_i to [0, 1], as the interface Fresnel functions do
    c = np.clip(np.asarray(cos_theta_i, dtype=np.float64), 0.0, 1.0)
    films = [_index(n, f"film {i}") for i, n in enumerate(n_films)]
    return c, lam, _index(n_substrate, "substrate"), films, d, n0.real


def amplitudes(cos_theta_i, wavelength_nm, n_substrate, n_films=(), d_films_nm=(), polarization: str = "s",
               n_incident=1.0):
    """Amplitude reflection and transmission coefficients (r, t) of a film stack for one polarization.

    Parameters
    ----------
    cos_theta_i : array_like
        Cosine of the incidence angle in the incident medium (clamped to [0, 1]).
    wavelength_nm : array_like, nm
        Vacuum wavelengths (broadcast against *cos_theta_i* and the indices).
    n_substrate : complex or array_like
        Substrate index n + ik (semi-infinite).
    n_films : sequence of complex or array_like
        Film indices, **from the substrate outwards** (each broadcast against the wavelengths).
    d_films_nm : sequence of float, nm
        Film thicknesses (≥ 0), in the order of *n_films*.
    polarization : {'s', 'p'}
    n_incident : float
        Index of the (non-absorbing) incident medium.

    Returns
    -------
    r, t : ndarray of complex
        Reflected and transmitted (into the substrate) electric field amplitude over the incident one, on the
        interface conventions of the module docstring; shape: the broadcast of every argument.

    References
    ----------
    .. [1] F. Abelès, Ann. Phys. (Paris) 12(5), 596–640, 706–782, 1950.
    .. [2] M. Born, E. Wolf, *Principles of Optics*, 7th ed., §1.6.4 (Airy formula of one film, eq. 1.6.(57)).
    .. [3] O. S. Heavens, *Optical Properties of Thin Solid Films*, 1955, §4.3 (Rouard's recurrence).
    .. [4] H. A. Macleod, *Thin-Film Optical Filters*, 4th ed., 2010, §2.6.
    """
    c, lam, ns, films, d, n0 = _check(cos_theta_i, wavelength_nm, n_substrate, n_films, d_films_nm, n_incident,
                                      polarization)
    s2 = n0 * n0 * (1.0 - c * c)                      # (n₀ sin θ_i)², conserved across the stack
    k0 = 2.0 * np.pi / lam
    media = [ns, *films, np.asarray(n0, dtype=np.complex128)]   # from the substrate up to the incident medium
    qs = [_q(n, s2) for n in media]
    with np.errstate(invalid="ignore", divide="ignore"):
        r, t = _interface(polarization, media[1], qs[1], media[0], qs[0])
        for j in range(1, len(media) - 1):           # add film j (media[j]) under medium j+1
            r_u, t_u = _interface(polarization, media[j + 1], qs[j + 1], media[j], qs[j])
            phase = np.exp(1j * k0 * qs[j] * d[j - 1])        # e^{iβ_j}, |.| ≤ 1 since Im q_j ≥ 0
            e2 = phase * phase
            den = 1.0 + r_u * r * e2
            r, t = (r_u + r * e2) / den, t_u * t * phase / den
    shape = np.broadcast_shapes(c.shape, lam.shape, *(np.shape(m) for m in media))
    grazing = np.broadcast_to(c <= 0.0, shape)
    # guard: at grazing incidence the stack reflects totally (the limit; the formulas may be 0/0 there)
    r = np.where(grazing, -1.0 + 0j, np.broadcast_to(r, shape))
    t = np.where(grazing, 0j, np.broadcast_to(t, shape))
    return r, t


def r_s(cos_theta_i, wavelength_nm, n_substrate, n_films=(), d_films_nm=(), n_incident=1.0):
    """Amplitude reflection coefficient of s-polarized light (:func:`amplitudes`).

    References
    ----------
    .. [1] M. Born, E. Wolf, *Principles of Optics*, 7th ed., §1.6; O. S. Heavens 1955, §4.3.
    """
    return amplitudes(cos_theta_i, wavelength_nm, n_substrate, n_films, d_films_nm, "s", n_incident)[0]


def r_p(cos_theta_i, wavelength_nm, n_substrate, n_films=(), d_films_nm=(), n_incident=1.0):
    """Amplitude reflection coefficient of p-polarized light (:func:`amplitudes`).

    References
    ----------
    .. [1] M. Born, E. Wolf, *Principles of Optics*, 7th ed., §1.6; O. S. Heavens 1955, §4.3.
    """
    return amplitudes(cos_theta_i, wavelength_nm, n_substrate, n_films, d_films_nm, "p", n_incident)[0]


def t_s(cos_theta_i, wavelength_nm, n_substrate, n_films=(), d_films_nm=(), n_incident=1.0):
    """Amplitude transmission coefficient (into the substrate) of s-polarized light (:func:`amplitudes`).

    References
    ----------
    .. [1] M. Born, E. Wolf, *Principles of Optics*, 7th ed., §1.6; O. S. Heavens 1955, §4.3.
    """
    return amplitudes(cos_theta_i, wavelength_nm, n_substrate, n_films, d_films_nm, "s", n_incident)[1]


def t_p(cos_theta_i, wavelength_nm, n_substrate, n_films=(), d_films_nm=(), n_incident=1.0):
    """Amplitude transmission coefficient (into the substrate; electric field) of p-polarized light.

    References
    ----------
    .. [1] M. Born, E. Wolf, *Principles of Optics*, 7th ed., §1.6; O. S. Heavens 1955, §4.3.
    """
    return amplitudes(cos_theta_i, wavelength_nm, n_substrate, n_films, d_films_nm, "p", n_incident)[1]


def _RT(cos_theta_i, wavelength_nm, n_substrate, n_films, d_films_nm, polarization, n_incident):
    """(R, T) of one polarization, or their means over s and p for ``"unpolarized"``."""
    if polarization == "unpolarized":
        Rs, Ts = _RT(cos_theta_i, wavelength_nm, n_substrate, n_films, d_films_nm, "s", n_incident)
        Rp, Tp = _RT(cos_theta_i, wavelength_nm, n_substrate, n_films, d_films_nm, "p", n_incident)
        return 0.5 * (Rs + Rp), 0.5 * (Ts + Tp)
    r, t = amplitudes(cos_theta_i, wavelength_nm, n_substrate, n_films, d_films_nm, polarization, n_incident)
    c = np.clip(np.asarray(cos_theta_i, dtype=np.float64), 0.0, 1.0)
    n0 = float(np.real(n_incident))
    ns = np.asarray(n_substrate, dtype=np.complex128)
    q_sub = _q(ns, n0 * n0 * (1.0 - c * c))
    flux = q_sub.real if polarization == "s" else (q_sub * np.conj(ns) / ns).real
    with np.errstate(invalid="ignore", divide="ignore"):
        T_ = np.where(t == 0, 0.0, flux / (n0 * c) * np.abs(t) ** 2)
    return np.abs(r) ** 2, T_


def R(cos_theta_i, wavelength_nm, n_substrate, n_films=(), d_films_nm=(), polarization: str = "unpolarized",
      n_incident=1.0):
    """Reflectance |r|² of the stack for ``"s"``, ``"p"`` or ``"unpolarized"`` (their mean) light.

    Parameters are those of :func:`amplitudes`.

    References
    ----------
    .. [1] M. Born, E. Wolf, *Principles of Optics*, 7th ed., §1.5.3, §1.6.4.
    .. [2] H. A. Macleod, *Thin-Film Optical Filters*, 4th ed., 2010, §2.6.
    """
    return _RT(cos_theta_i, wavelength_nm, n_substrate, n_films, d_films_nm, _pol(polarization), n_incident)[0]


def T(cos_theta_i, wavelength_nm, n_substrate, n_films=(), d_films_nm=(), polarization: str = "unpolarized",
      n_incident=1.0):
    """Transmittance into the substrate: the normal Poynting flux Re(q_sub)/q₀ |t_s|² (s) or
    Re(q_sub n_sub*/n_sub)/q₀ |t_p|² (p), or their mean (``"unpolarized"``).

    References
    ----------
    .. [1] M. Born, E. Wolf, *Principles of Optics*, 7th ed., §1.5.3 (energy flux of the transmitted wave).
    .. [2] H. A. Macleod, *Thin-Film Optical Filters*, 4th ed., 2010, §2.6 (transmittance into an absorbing
       medium).
    """
    return _RT(cos_theta_i, wavelength_nm, n_substrate, n_films, d_films_nm, _pol(polarization), n_incident)[1]


def A(cos_theta_i, wavelength_nm, n_substrate, n_films=(), d_films_nm=(), polarization: str = "unpolarized",
      n_incident=1.0):
    """Absorptance of the films: A = 1 − R − T (energy conservation; light entering the substrate counts in T).

    References
    ----------
    .. [1] H. A. Macleod, *Thin-Film Optical Filters*, 4th ed., 2010, §2.6 (absorptance of a coating).
    """
    Rv, Tv = _RT(cos_theta_i, wavelength_nm, n_substrate, n_films, d_films_nm, _pol(polarization), n_incident)
    return 1.0 - Rv - Tv


def _pol(polarization: str) -> str:
    if polarization not in (*POLARIZATIONS, "unpolarized"):
        raise WaveopticsError(f"polarization {polarization!r} is not allowed; use unpolarized, s or p")
    return polarization
