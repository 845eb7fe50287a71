/* Common definitions for waveoptics kernels.
 * Build with -DWO_DOUBLE=1 for float64 (the host checks cl_khr_fp64 first), otherwise float32.
 *   real_t : the real type;  cplx_t : the matching pyopencl complex type;  CX(fn) : cfloat_fn / cdouble_fn
 */
#ifndef WO_COMMON_H
#define WO_COMMON_H

#ifdef WO_DOUBLE
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
#define PYOPENCL_DEFINE_CDOUBLE
typedef double real_t;
#define CX(fn) cdouble_##fn
#define cplx_t cdouble_t
#define R(x) (x)
#else
typedef float real_t;
#define CX(fn) cfloat_##fn
#define cplx_t cfloat_t
#define R(x) (x##f)
#endif

#include <pyopencl-complex.h>

#define WO_PI R(3.14159265358979323846)

/* Clamp to [lo, hi]; used for cosines before sqrt/acos (pbrt-v4 style guards). */
inline real_t wo_clamp(real_t x, real_t lo, real_t hi) { return fmin(fmax(x, lo), hi); }

#endif
