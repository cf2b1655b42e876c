/* Self-test input for check_nofloat.sh: must be rejected. */
long long scale(long long v, double k);
long long scale(long long v, double k)
{
	return (long long)((double)v * k);
}
