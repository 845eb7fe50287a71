"""The polarization of the diffracted lobe for Mitsuba's polarized variants: the Mueller matrix of a 2×2 complex Jones
matrix, and the first-order (Rayleigh-Rice) Jones matrix of a rough interface with the s/p frames it is written in.

Complex numbers are (real, imaginary) pairs: :func:`mueller_from_jones` is plain arithmetic (Python floats, NumPy or
Dr.Jit arrays); the other functions take the Dr.Jit module ``dr`` for square roots and selects, so they run in the
scalar, LLVM and CUDA variants alike.

Conventions (those of :func:`waveoptics.scatter.q_factors` and of Mitsuba 3's ``mueller.h``):

* ω_i, ω_o point away from the surface (towards the light and towards the viewer), the macro normal is z; the light
  travels along k_i = −ω_i and then k_o = ω_o.
* s = ẑ × ω / |ẑ × ω| for each of the two directions, p = k × s (k the direction of travel). Mitsuba's Stokes frame
  of a beam travelling along k is (x = its basis vector, y = k × x), so (s, p) is a Stokes frame of Mitsuba with s
  as its basis vector (the example in ``rotate_stokes_basis``'s documentation fixes y = k × x). At normal
  incidence the plane of incidence is the x–z plane, for ω_o along the normal o = −(ω_i's azimuth), as
  :func:`waveoptics.scatter.angles.scattering_angles` takes them. That Germer's q factors are written in these
  frames (p = k × s for both beams, not s × k) is what makes the first-order field at normal incidence keep the
  incident polarization in the laboratory frame, as rotational symmetry requires (tests/test_mitsuba_polarized.py).
* Jones matrix J = [[J_ss, J_sp], [J_ps, J_pp]] as E_out = J E_in in those frames (row: scattered polarization,
  column: incident), so J = [[q_ss, q_ps], [q_sp, q_pp]] with the library's q_ab (a incident, b scattered).
* Stokes vector (S0, S1, S2, S3) = (|E_s|² + |E_p|², |E_s|² − |E_p|², 2 Re E_s E_p*, 2 Im E_s E_p*) for the
  e^{−iωt} amplitudes of the library (ε = (n + iκ)², κ ≥ 0): Mitsuba's ``specular_reflection(cos θ, η)`` is the
  Mueller matrix of J = diag(r_s, r_p) (Fresnel, Verdet's sign of r_p) in this convention (it conjugates η to
  n − iκ and uses S3 with the opposite sign, which is the same Stokes vector).

References
----------
.. [1] M. Born, E. Wolf, *Principles of Optics*, 7th ed., §10.8.3 (Stokes parameters) and §1.5.2 (Fresnel).
.. [2] R. A. Chipman, W. S. T. Lam, G. Young, *Polarized Light and Optical Systems*, CRC 2018, §6.9
   (M = A (J ⊗ J*) A⁻¹, the Mueller matrix of a Jones matrix; non-depolarizing Mueller matrices).
.. [3] T. A. Germer, "Angular dependence and polarization of out-of-plane optical scattering from particulate
   contamination, subsurface defects, and surface microroughness", Appl. Opt. 36(33), 8798–8805, 1997
   (q_ss, q_sp, q_ps, q_pp and their s/p frames).
.. [4] W. Jakob et al., Mitsuba 3, ``include/mitsuba/render/mueller.h`` (``specular_reflection``,
   ``stokes_basis``, ``rotate_mueller_basis``: the Stokes frame (x, k × x)).
"""
from __future__ import annotations

__all__ = ["mueller_from_jones", "rayleigh_rice_jones", "sp_basis", "sp_frames"]


def _cmul(x, y):
    return (x[0] * y[0] - x[1] * y[1], x[0] * y[1] + x[1] * y[0])


def _cmulconj(x, y):
    """x · conj(y)."""
    return (x[0] * y[0] + x[1] * y[1], x[1] * y[0] - x[0] * y[1])


def _abs2(x):
    return x[0] * x[0] + x[1] * x[1]


def _csqrt(dr, z):
    """Principal square root of z = (re, im) (Re ≥ 0; the sign of im kept on the negative real axis), in the stable
    form of :meth:`waveoptics.renderers.drjit_twoscale.DrJitTwoScale.F`."""
    zr, zi = z
    r = dr.sqrt(zr * zr + zi * zi)
    big = dr.sqrt(dr.maximum(0.5 * (r + dr.abs(zr)), 0.0))
    safe = dr.select(big > 0, big, 1.0)          # guard: z = 0 has root 0
    re = dr.select(zr >= 0, big, dr.abs(zi) / (2.0 * safe))
    im = dr.select(zr >= 0, zi / (2.0 * safe), dr.select(zi >= 0, big, -big))
    return re, im


def mueller_from_jones(J):
    """Mueller matrix (4×4 nested lists of reals) of the Jones matrix J = ((a, b), (c, d)), each entry a complex
    number as a (real, imaginary) pair of floats or arrays: M_kl = ½ tr(σ_k J σ_l J†), which is A (J ⊗ J*) A⁻¹.

    σ_0 = I, σ_1 = diag(1, −1), σ_2 = [[0, 1], [1, 0]], σ_3 = [[0, i], [−i, 0]]: the Stokes vector
    (|E_x|² + |E_y|², |E_x|² − |E_y|², 2 Re E_x E_y*, 2 Im E_x E_y*) of the module's convention.

    References
    ----------
    .. [1] R. A. Chipman, W. S. T. Lam, G. Young, *Polarized Light and Optical Systems*, CRC 2018, §6.9.
    .. [2] M. Born, E. Wolf, *Principles of Optics*, 7th ed., §10.8.3.
    """
    (a, b), (c, d) = J
    aa, bb, cc, dd = _abs2(a), _abs2(b), _abs2(c), _abs2(d)
    ac, bd = _cmulconj(a, c), _cmulconj(b, d)
    ab, cd = _cmulconj(a, b), _cmulconj(c, d)
    ad, bc = _cmulconj(a, d), _cmulconj(b, c)
    # B_l = J σ_l J†, as (B_00, B_11, B_01) for l = 0..3 (B is Hermitian)
    B = [(aa + bb, cc + dd, (ac[0] + bd[0], ac[1] + bd[1])),
         (aa - bb, cc - dd, (ac[0] - bd[0], ac[1] - bd[1])),
         (2.0 * ab[0], 2.0 * cd[0], (ad[0] + bc[0], ad[1] + bc[1])),
         (-2.0 * ab[1], -2.0 * cd[1], (bc[1] - ad[1], ad[0] - bc[0]))]     # i (a d* − b c*)
    M = [[None] * 4 for _ in range(4)]
    for l, (b00, b11, b01) in enumerate(B):
        M[0][l] = 0.5 * (b00 + b11)
        M[1][l] = 0.5 * (b00 - b11)
        M[2][l] = b01[0]
        M[3][l] = b01[1]
    return M


def sp_basis(dr, w, ex, ey):
    """(s_x, s_y, sin θ) of s = ẑ × ω / |ẑ × ω| for the direction ω (away from the surface; s_z = 0); where ω is
    the normal, s = ẑ × (ex, ey, 0) for the given unit azimuth (ex, ey)."""
    sin_t = dr.sqrt(dr.maximum(w.x * w.x + w.y * w.y, 0.0))
    ok = sin_t > 0
    inv = 1.0 / dr.select(ok, sin_t, 1.0)        # guard: the normal direction takes the given azimuth
    ux, uy = dr.select(ok, w.x * inv, ex), dr.select(ok, w.y * inv, ey)
    return -uy, ux, sin_t


def sp_frames(dr, wi, wo):
    """The s axes of the incident and scattered frames and the scattering azimuth for the pair (ω_i, ω_o):
    ((s_x, s_y, sin θ_i), (s_x, s_y, sin θ_o), (cos φ_s, sin φ_s)), φ_s measured from the specular side of the
    plane of incidence (as :func:`waveoptics.scatter.angles.scattering_angles`)."""
    six, siy, sin_i = sp_basis(dr, wi, 1.0, 0.0)
    ex, ey = siy, -six                                   # ω_i's azimuth (x at normal incidence)
    sox, soy, sin_o = sp_basis(dr, wo, -ex, -ey)
    ox, oy = soy, -sox                                   # ω_o's azimuth
    return (six, siy, sin_i), (sox, soy, sin_o), (-(ex * ox + ey * oy), -(ex * oy - ey * ox))


def rayleigh_rice_jones(dr, wi, wo, eps, frames=None):
    """The first-order Jones matrix J = [[q_ss, q_ps], [q_sp, q_pp]] of a slightly rough interface of relative
    permittivity *eps* = (re, im) for the pair (ω_i, ω_o), up to one complex factor common to its four entries (it
    drops out of the normalized Mueller matrix), in the frames of :func:`sp_frames` (*frames*: their value, if
    already computed). Entries as (real, imaginary) pairs.

    q_ss = (ε − 1) cosφ_s / (d_si d_so),  q_sp = −(ε − 1) r_o sinφ_s / (d_si d_po),
    q_ps = −(ε − 1) r_i sinφ_s / (d_pi d_so),  q_pp = (ε − 1) (ε sinθ_i sinθ_o − r_i r_o cosφ_s) / (d_pi d_po),
    r = √(ε − sin²θ), d_s = cosθ + r, d_p = ε cosθ + r; multiplied here by d_si d_so d_pi d_po / (ε − 1).

    References
    ----------
    .. [1] T. A. Germer, Appl. Opt. 36(33), 8798–8805, 1997, eqs. (17)–(20).
    .. [2] J. M. Elson, J. M. Bennett, "Vector scattering theory", Opt. Eng. 18(2), 116–124, 1979.
    """
    (_, _, sin_i), (_, _, sin_o), (cphi, sphi) = frames if frames is not None else sp_frames(dr, wi, wo)
    ci, co = dr.clip(wi.z, 0.0, 1.0), dr.clip(wo.z, 0.0, 1.0)
    er, ei = eps
    ri = _csqrt(dr, (er - sin_i * sin_i, ei))
    ro = _csqrt(dr, (er - sin_o * sin_o, ei))
    ds_i, ds_o = (ci + ri[0], ri[1]), (co + ro[0], ro[1])
    dp_i, dp_o = (er * ci + ri[0], ei * ci + ri[1]), (er * co + ro[0], ei * co + ro[1])
    rr = _cmul(ri, ro)
    pp = (er * sin_i * sin_o - rr[0] * cphi, ei * sin_i * sin_o - rr[1] * cphi)
    q_ss = _cmul(dp_i, dp_o)
    q_sp = _cmul(_cmul(ro, ds_o), dp_i)
    q_ps = _cmul(_cmul(ri, ds_i), dp_o)
    q_pp = _cmul(pp, _cmul(ds_i, ds_o))
    return ((_scale(q_ss, cphi), _scale(q_ps, -sphi)), (_scale(q_sp, -sphi), q_pp))


def _scale(x, r):
    return (x[0] * r, x[1] * r)
