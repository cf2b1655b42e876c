/* The fixed-point helpers as a build without 128-bit integers compiles
 * them (a Cortex-M), so a host test can compare both paths bit for bit. */
#undef __SIZEOF_INT128__
#include "firmware/fx.h"

q32_t fx_mul_portable(q32_t a, q32_t b);
q32_t fx_mul_portable(q32_t a, q32_t b) { return fx_mul(a, b); }
