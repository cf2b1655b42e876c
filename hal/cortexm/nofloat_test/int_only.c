/* Self-test input for check_nofloat.sh: 64-bit division calls
 * __aeabi_ldivmod on a Cortex-M0, which is integer and must pass. */
long long ratio(long long a, long long b);
long long ratio(long long a, long long b)
{
	return b ? a / b : 0;
}
