/* The number type of the VehicleService boundary and of the configuration.
 *
 * On a host it is double, as the IDL has it. A board without a
 * double-precision FPU builds with VS_REAL_Q32: the same code then carries
 * Q32.32 fixed point (the tick's own unit, fx.h), the links convert the
 * wire's IEEE doubles and the console's decimals to it with integer code
 * (proto/numparse.c), and no floating-point helper is linked at all. That
 * is 6 KiB of soft-double the image does not carry (docs/mcu.md).
 *
 * Q32's range is +-2^31 (2.1e9 in mm, deg, mm/s, ...), well beyond every
 * bound the unit accepts (positions 1e6 mm, jerks 1e7 mm/s^3). A value
 * outside it saturates to +-VS_REAL_HUGE, which every bound refuses as too
 * large; NaN and infinity become VS_REAL_NAN, which every range refuses as
 * not a number. So a board answers each request as the host does.
 */
#ifndef VS_REAL_H
#define VS_REAL_H

#include <stdint.h>

#ifdef VS_REAL_Q32
typedef int64_t vs_real_t;
/* A decimal constant in Q32, folded by the compiler (constants only). */
#define VS_REAL(x)   ((vs_real_t)((x)*4294967296.0 + ((x) < 0 ? -0.5 : 0.5)))
#define VS_REAL_NAN  INT64_MIN
#define VS_REAL_HUGE INT64_MAX
#define VS_REAL_ONE  (INT64_C(1) << 32)
/* Neither NaN nor infinity. */
#define vs_real_finite(x) ((x) != VS_REAL_NAN)
#define vs_real_nan(x)	  ((x) == VS_REAL_NAN)
/* An integer (|i| < 2^31) as a vs_real_t. */
#define vs_real_int(i) ((vs_real_t)(i)*VS_REAL_ONE)
#else
typedef double vs_real_t;
#define VS_REAL(x)	  (x)
#define VS_REAL_ONE	  1.0
/* Not NaN, not infinite (libc-free). */
#define vs_real_finite(x) ((x) == (x) && (x) >= -1e300 && (x) <= 1e300)
#define vs_real_nan(x)	  ((x) != (x))
#define vs_real_int(i)	  ((double)(i))
#endif

#endif
