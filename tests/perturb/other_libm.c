/* The C library's elementary functions, one ulp up when numpy's ufunc loops call them (tests/test_same_bits.py).
 *
 * Preloaded (LD_PRELOAD) into a process, this library's exp, log, pow, sin, ... stand in front of the C library's.
 * Each looks at who called it: numpy's ufunc module (_multiarray_umath) gets the C library's result moved one ulp
 * up, as another SIMD implementation of the same function may round it (numpy's AVX-512 loops on an AVX-512
 * machine); every other caller (bogie's numba kernels and ufuncs, Python's math module, scipy.special, numpy's random
 * generators) gets the C library's bits unchanged. So a result that goes through numpy's elementary functions,
 * ``**`` on arrays included, changes its bits in such a process, and one that goes through bogie.numerics does not.
 */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <math.h>
#include <string.h>

static int from_numpy(void *where) {
    Dl_info info;
    if (!dladdr(where, &info) || info.dli_fname == NULL) return 0;
    return strstr(info.dli_fname, "_multiarray_umath") != NULL;
}

static double up(double r) { return isfinite(r) ? nextafter(r, INFINITY) : r; }

#define ONE(name)                                                                  \
    double name(double x) {                                                        \
        static double (*real)(double) = 0;                                         \
        if (!real) real = (double (*)(double))dlsym(RTLD_NEXT, #name);             \
        double r = real(x);                                                        \
        return from_numpy(__builtin_return_address(0)) ? up(r) : r;               \
    }
#define TWO(name)                                                                  \
    double name(double x, double y) {                                              \
        static double (*real)(double, double) = 0;                                 \
        if (!real) real = (double (*)(double, double))dlsym(RTLD_NEXT, #name);     \
        double r = real(x, y);                                                     \
        return from_numpy(__builtin_return_address(0)) ? up(r) : r;               \
    }

ONE(exp) ONE(exp2) ONE(expm1) ONE(log) ONE(log2) ONE(log10) ONE(log1p)
ONE(sin) ONE(cos) ONE(tan) ONE(asin) ONE(acos) ONE(atan)
ONE(sinh) ONE(cosh) ONE(tanh) ONE(asinh) ONE(acosh) ONE(atanh) ONE(cbrt)
TWO(pow) TWO(atan2) TWO(hypot)
