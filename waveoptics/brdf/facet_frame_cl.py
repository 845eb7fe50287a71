"""OpenCL twin of the facet-frame quadrature's per-cell sum (``kernels/facet_frame.cl``): Walter's integral over
facet normals of :func:`waveoptics.brdf.facet_frame_diffraction`, each facet's nano lobe read from the tables
over local incidence, for PSD statistics (the nodes laid out about each cell's half-vector).

The NumPy twin is the node loop of :func:`waveoptics.brdf.facet_frame_diffraction` (``backend="numpy"``); the
kernel takes the same nodes (:func:`waveoptics.brdf.facet.unit_nodes` through the NDF's D(m) cos θ_m sampler and
the nano lobe's radial law), the same balance-heuristic weights, G, facet frames and bilinear table reads, in the
device's float32 (or float64 where asked and supported) where NumPy uses float64 around float32 tables.

References
----------
.. [1] B. Walter, S. Marschner, H. Li, K. Torrance, EGSR 2007, eq. (14) (a BRDF carried by each facet).
.. [2] E. Veach, PhD thesis, Stanford 1997, §9.2 (balance heuristic).
.. [3] T. Duff et al., "Building an Orthonormal Basis, Revisited", JCGT 6(1), 2017.
.. [4] R. G. Priest, T. A. Germer, Proc. 2000 MSS Specialty Group on Passive Sensors, 2000 (facet s/p frames).
"""
from __future__ import annotations

import threading

import numpy as np

from ..errors import FieldError, unknown
from ..runtime import build_options, build_program, get_runtime, opencl_available, program_kernel
from ..scatter.tangent_blend import TANGENT_PLANE_BLEND_DEG
from .facet import BRIDGE_NODES, COS_LEVELS, bridge_offsets, half_vector_base, ndf_node_base
from .ndf import ndf_by_name
from .opencl import ndf_shape_parameter
from .shadowing import shadowing_by_name

__all__ = ['FACET_FRAME_BACKENDS', 'kernel_reason', 'facet_frame_backend', 'facet_frame_kernel',
           'warm_facet_frame_kernel', 'facet_frame_sum_cl']

#: the per-cell sum of :func:`waveoptics.brdf.facet_frame_diffraction`: ``opencl`` (``kernels/facet_frame.cl``),
#: ``numpy`` (its twin), ``auto`` (the kernel where an OpenCL device exists and :func:`kernel_reason` allows it)
FACET_FRAME_BACKENDS = ("auto", "opencl", "numpy")
#: wavelengths the kernel accumulates per pass (``WO_NL`` in ``kernels/facet_frame.cl``)
KERNEL_WAVELENGTHS = 32
#: work-group size (a multiple of a GPU's warp): on PoCL's 2-thread CPU device (128² cells, 25 λ, a loaded
#: machine) 64 items per group took 0.44-0.50 s wall where PoCL's own choice took 0.72 s, at the same CPU time
LOCAL_SIZE = 64


def kernel_reason(micro, nano) -> str | None:
    """Why the kernel cannot take the facet-frame sum of *micro* and *nano* (a sentence), or None: a height field
    (its nodes are the NDF sampler's for ω_i and Sobol half-vector nodes, not the symmetric layout), an NDF without
    an OpenCL twin (``NDF.cl_id``). Every masking-shadowing form of :data:`waveoptics.brdf.SHADOWINGS` has its
    kernel switch."""
    if nano.surface is not None:
        return "a height field's facet quadrature stays on NumPy"
    if ndf_by_name(micro.ndf).cl_id is None:
        return f"NDF {micro.ndf!r} has no OpenCL twin"
    return None


def facet_frame_backend(backend: str, micro, nano) -> str:
    """``opencl`` or ``numpy``: the backend *backend* (one of :data:`FACET_FRAME_BACKENDS`) takes for *micro* and
    *nano*; ``opencl`` asked for a configuration the kernel does not take (:func:`kernel_reason`) is refused."""
    if backend not in FACET_FRAME_BACKENDS:
        raise unknown("backend", backend, FACET_FRAME_BACKENDS, field="backend")
    why = kernel_reason(micro, nano)
    if backend == "opencl" and why is not None:
        raise FieldError("{backend} 'opencl' of the facet-frame quadrature is not available: " + why, "backend")
    if backend == "auto":
        return "opencl" if why is None and opencl_available() else "numpy"
    return backend


def _half_vector_tables(rad, nb: int):
    """The data of the antithetic half-vector nodes of :func:`waveoptics.brdf.facet_frame_diffraction` for the
    kernel: :func:`waveoptics.brdf.facet.half_vector_base` (n_base, radii (COS_LEVELS, n_base)), the radii's radial
    density per unit area of the direction-cosine plane (:meth:`waveoptics.brdf.facet.NanoRadial.pdf_r`), and
    (cos φ, sin φ) (nb, 2) of the node azimuths about h."""
    n_base, radii, phi = half_vector_base(rad, nb)
    pdf = rad.pdf_r(np.arange(COS_LEVELS)[:, None], radii)
    return n_base, radii, pdf, np.stack([np.cos(phi), np.sin(phi)], axis=-1)


def facet_frame_kernel(micro, *, mix: bool, blend: bool, projected: bool, device=None, precision: str = "float32"):
    """(runtime, real dtype, kernel): the kernel ``facet_frame_sum`` of ``kernels/facet_frame.cl`` for *micro*'s
    NDF, masking-shadowing form and isotropy, built (once per switch set, :func:`waveoptics.runtime.build_program`)
    with its switches: *mix* another polarization's tables (``WO_MIX``), *blend* first-order tables
    (``WO_BLEND``), *projected* tables on the equal-area projection (``WO_EQUI``); the kernel object is the calling
    thread's own (:func:`waveoptics.runtime.program_kernel`)."""
    kw = micro.kw()
    spec = ndf_by_name(kw["ndf"])
    ay = kw["alpha_y"] if kw["alpha_y"] is not None else kw["alpha"]
    rt = get_runtime(device)
    dt = rt.real_dtype(precision)
    defines = (f"-DWO_NDF={spec.cl_id}", f"-DWO_SHADOWING={shadowing_by_name(kw['shadowing'])[1]}",
               f"-DWO_ISO={int(ay == kw['alpha'])}", f"-DWO_MIX={int(bool(mix))}", f"-DWO_BLEND={int(bool(blend))}",
               f"-DWO_EQUI={int(bool(projected))}",
               *(f"-DWO_BLEND_{n}={float(np.radians(t))!r}" for n, t in zip("01", TANGENT_PLANE_BLEND_DEG)))
    return rt, dt, program_kernel(build_program(rt, "facet_frame.cl", build_options(dt, defines)), "facet_frame_sum")


def warm_facet_frame_kernel(micro, nano, diffraction, polarization: str = "unpolarized", *, device=None,
                            precision: str = "float32"):
    """Build, in a background thread, the kernel :func:`facet_frame_sum_cl` will take for *micro* and *nano*
    (PSD statistics; the *diffraction* model, a :class:`waveoptics.scatter.DiffractionModel`, and *polarization*
    set its switches), so that the OpenCL platform's start, the compiler run (0.5-2 s on PoCL, less with its
    kernel cache) and PoCL's compile of the work-group function at a kernel's first launch (here a launch over no
    cells) overlap the NumPy work that comes first (the coherent lobe, the facet tables). Returns the thread (join
    it before the process ends), or None where :func:`facet_frame_backend` would not take the kernel. A failure
    here is left to the real call, which raises it."""
    if kernel_reason(micro, nano) is not None:
        return None
    mix = diffraction.perturbative and polarization in ("s", "p")
    blend = not diffraction.perturbative

    def warm():
        from ..errors import WaveopticsError

        try:
            import pyopencl as cl
        except ImportError:   # the real call names the missing dependency
            return
        try:
            if not opencl_available():
                return
            rt, dt, kern = facet_frame_kernel(micro, mix=mix, blend=blend, projected=True, device=device,
                                              precision=precision)
            dummy = cl.Buffer(rt.context, cl.mem_flags.READ_WRITE, 64)
            kern(rt.queue, (LOCAL_SIZE,), (LOCAL_SIZE,), *[dummy] * 15, *[dt(0)] * 11, *[np.int32(0)] * 12).wait()
        except (WaveopticsError, cl.Error):   # the real call raises it where it belongs
            return

    thread = threading.Thread(target=warm, name="waveoptics-facet-frame-kernel", daemon=True)
    thread.start()
    return thread


_tables: dict = {}
_tables_lock = threading.Lock()


def _table_buffer(rt, stack):
    """A device copy of the facet table *stack* (float32), made once per (context, table) and kept for the next
    incidences (the tables are cached on the :class:`waveoptics.brdf.Nano`); the two latest are kept."""
    import pyopencl as cl

    key = (id(rt.context), id(stack))
    with _tables_lock:   # threads share the kept copies (a render's or a study's tasks)
        hit = _tables.get(key)
        if hit is None or hit[0] is not stack:
            while len(_tables) >= 2:
                _tables.pop(next(iter(_tables)))
            data = np.ascontiguousarray(stack, dtype=np.float32)
            hit = _tables[key] = (stack, cl.Buffer(rt.context, cl.mem_flags.READ_ONLY | cl.mem_flags.COPY_HOST_PTR,
                                                   hostbuf=data))
        return hit[1]


def facet_frame_sum_cl(wi, wo, h, cos_d, level, Lo, Li, micro, nodes, rad, stack, stack_other, table_grid,
                       thetas_deg, *, device=None, precision: str = "float32", first=None, projected=False,
                       graze=None, bridge=None):
    """Σ over the NDF and half-vector nodes of the balance-heuristic weight |ω_i·m| D G / (cos θ_i cos θ_o
    (N_a p_a + N_b p_b)) times g = f_nano cos θ_o read from the facet tables, per cell: the kernel
    ``facet_frame_sum`` of ``kernels/facet_frame.cl``.

    Parameters
    ----------
    wi : ndarray (3,)
        Unit vector towards the light.
    wo, h : ndarray (n_cells, 3)
        The cells' directions and half-vectors.
    cos_d : ndarray (n_cells,)
        cos θ_d = h·ω_i; *level* (n_cells,) int: its level of the radial law *rad*
        (:class:`waveoptics.brdf.facet.NanoRadial`).
    Lo : ndarray (n_cells,); Li : float
        Smith Λ of ω_o and ω_i.
    micro : Micro
        Its NDF (one with ``cl_id``), α, shape parameter and masking-shadowing form.
    nodes : (int, int)
        (N_a, N_b).
    stack, stack_other : ndarray (n_θ, n_v, n_u, n_λ) float32
        g at the local incidences *thetas_deg* (degrees) on *table_grid*; *stack_other*: the other polarization's
        (s or p light of a Rayleigh-Rice lobe, mixed by cos²η_i), or None.
    first : ndarray (n_θ, n_v, n_u, n_λ) float32, optional
        The first-order facet tables f_RR / F cos θ_o of :func:`waveoptics.brdf.facet_frame_diffraction` (*stack*
        then holds the tangent-plane lobe f_K cos θ_o): each facet adds W stack + (1 − W) first, W = w(θ_i')
        w(θ_o') of :mod:`waveoptics.scatter.tangent_blend` at its exact local angles (not with *stack_other*).
    projected : bool
        Whether *table_grid* is Lambert's azimuthal equal-area projection of PSD statistics' tables
        (:func:`waveoptics.brdf.facet_table_grid`) rather than direction cosines; their first-order tables
        (*first*, or a Rayleigh-Rice *stack* and *stack_other*) then hold q = g / cos²θ_o, multiplied by each
        facet's exact cos²θ_o' (:func:`waveoptics.brdf.facet_frame_diffraction`).
    graze : ndarray (n_cells,) bool, optional
        Cells that take 2 N_a NDF normals (:func:`waveoptics.brdf.grazing_cells`); none by default.
    bridge : (ndarray (n_cells, 3), ndarray (n_cells, 2), ndarray (n_cells,)), optional
        Each cell's bridge point, its Gaussian's widths and its weight β (:func:`waveoptics.brdf.facet.bridge_point`;
        β 0: none): :data:`waveoptics.brdf.facet.BRIDGE_NODES` normals about it
        (:func:`waveoptics.brdf.facet.bridge_nodes`) join the balance heuristic, counted β times. None: none.
    device : str, optional
        Device spec (:func:`waveoptics.runtime.get_runtime`).
    precision : {'float32', 'float64'}
        Device arithmetic (float64 needs the device's fp64); the tables stay float32.

    Returns
    -------
    ndarray (n_cells, n_λ), float64

    References
    ----------
    .. [1] B. Walter et al., EGSR 2007, eq. (14); §5.3 (sampling normals).
    .. [2] E. Veach, PhD thesis, 1997, §9.2 (balance heuristic of several techniques).
    .. [3] R. G. Priest, T. A. Germer, Proc. 2000 MSS Specialty Group on Passive Sensors, 2000.
    """
    import pyopencl as cl
    import pyopencl.array as cla

    kw = micro.kw()
    spec = ndf_by_name(kw["ndf"])
    ax = kw["alpha"]
    ay = kw["alpha_y"] if kw["alpha_y"] is not None else ax
    c = ndf_shape_parameter(spec, kw["ndf_shape"])
    na, nb = (int(x) for x in nodes)
    if first is not None and stack_other is not None:
        raise FieldError("the facet tables take either another polarization's tables or first-order tables, "
                         "not both", "first")
    rt, dt, kern = facet_frame_kernel(micro, mix=stack_other is not None, blend=first is not None,
                                      projected=projected, device=device, precision=precision)
    q = rt.queue
    m0, _, _ = ndf_node_base(na, ndf=kw["ndf"], ax=ax, ay=ay, c=kw["ndf_shape"])   # an anisotropic NDF's: unstretched
    graze = np.zeros(wo.shape[0], bool) if graze is None else np.asarray(graze, bool)
    m0_hi = ndf_node_base(2 * na, ndf=kw["ndf"], ax=ax, ay=ay, c=kw["ndf_shape"])[0] if graze.any() else m0
    n_base, radii, hv_pdf, hv_phi = _half_vector_tables(rad, nb)
    phi = np.arctan2(h[:, 1], h[:, 0])
    mc, bw, beta = bridge if bridge is not None else (h, np.zeros((h.shape[0], 2)), np.zeros(h.shape[0]))
    cell = np.column_stack([wo, h, np.cos(phi), np.sin(phi), cos_d, Lo, graze, mc,
                            np.where(beta[:, None] > 0, bw, 0.0), beta])
    n_cells = cell.shape[0]
    n_th, n_v, n_u, n_lam = stack.shape

    def dev(a, dtype=dt):
        return cla.to_device(q, np.ascontiguousarray(a, dtype=dtype).ravel())

    args = [dev(cell), dev(level, np.int32), dev(m0), dev(m0_hi), dev(radii), dev(hv_pdf), dev(hv_phi), dev(rad.edges / rad.k),
            dev(rad.density * rad.k ** 2), dev(np.radians(thetas_deg)),
            dev(np.stack([np.cos(np.radians(thetas_deg)), np.sin(np.radians(thetas_deg))], axis=-1))]
    tab = _table_buffer(rt, stack)
    second = stack_other if first is None else first
    tab_other = tab if second is None else _table_buffer(rt, second)
    bc = dev(bridge_offsets(BRIDGE_NODES))
    out = cla.empty(q, max(n_cells * n_lam, 1), dt)
    g0, g1 = table_grid.u_range[0], table_grid.v_range[0]
    scalars = [dt(x) for x in (*wi, Li, ax, ay, c, g0, g1, table_grid.du, table_grid.dv)]
    ints = [np.int32(x) for x in (n_cells, na, nb, BRIDGE_NODES, n_base, rad.edges.size - 1, n_th, n_u, n_v, n_lam)]
    for l0 in range(0, n_lam, KERNEL_WAVELENGTHS):
        nl = min(KERNEL_WAVELENGTHS, n_lam - l0)
        kern(q, (-(-max(n_cells, 1) // LOCAL_SIZE) * LOCAL_SIZE,), (LOCAL_SIZE,), *[a.data for a in args], tab,
             tab_other, bc.data, out.data, *scalars, *ints, np.int32(l0), np.int32(nl))
    cl.enqueue_barrier(q)
    return out.get()[:n_cells * n_lam].reshape(n_cells, n_lam).astype(np.float64)
