#!/bin/sh
# Fails (exit 1) when any of the given ARM objects or archives references a
# floating-point helper: the AEABI soft-float routines (__aeabi_d*, __aeabi_f*,
# conversions to and from integers), libgcc's generic ones (__adddf3,
# __fixdfsi, __extendsfdf2, ...), or libm. Integer helpers (__aeabi_ldivmod,
# __aeabi_uidiv, __aeabi_lmul, ...) are fine.
#   check_nofloat.sh NM FILE...
set -eu
nm=$1; shift
bad=$("$nm" -u -A "$@" | awk '
	{ sym = $NF; file = $1; sub(/:$/, "", file) }
	sym ~ /^__aeabi_(d|f|cd|cf|i2d|i2f|ui2d|ui2f|l2d|l2f|ul2d|ul2f|h2f|f2h)/ ||
	sym ~ /^__[a-z]*(sf|df|tf|xf|hf)[0-9]?[a-z]*[0-9]?$/ ||
	sym ~ /^(sqrtf?|sinf?|cosf?|tanf?|atan2f?|atanf?|floorf?|ceilf?|fabsf?|fmodf?|powf?|expf?|logf?|l?lroundf?|roundf?|hypotf?)$/ {
		print "  " file ": " sym
	}')
if [ -n "$bad" ]; then
	echo "floating point referenced in the board image:"
	echo "$bad"
	exit 1
fi
