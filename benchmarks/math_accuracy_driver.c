// SPDX-License-Identifier: GPL-2.0-only OR MIT
/*
 * math_accuracy_driver.c - measures the runtime's math functions against
 * glibc's libm.  Built and run by benchmarks/math_accuracy.py.
 *
 *   math_accuracy_driver FUNC TYPE DIST LO HI N SEED
 *     FUNC  sqrt exp ln log sin cos tan asin acos atan atan2 expt
 *     TYPE  lreal | real
 *     DIST  lin (uniform in [LO, HI]) | log (sign * 10^uniform[LO, HI]) |
 *           posl (10^uniform[LO, HI]) | edge (the fixed edge-case list)
 *   For two-argument functions the second argument (y of EXPT, x of ATAN2)
 *   comes from the same distribution, except EXPT with lin, whose second
 *   argument is uniform in [-60, 60].
 * Prints: max_ulp worst_x worst_y got ref mismatches count
 *   ULP of the reference value; the REAL functions are compared against the
 *   double result of glibc (so a correctly rounded REAL shows <= 0.5).
 *   A mismatch is a NaN/Inf/finite disagreement (never expected).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "iec_real.h"

static unsigned long long rng;

static double urand(void)
{
	rng ^= rng << 13;
	rng ^= rng >> 7;
	rng ^= rng << 17;
	return (double)(rng >> 11) * 0x1p-53;
}

static double ulp_d(double r)
{
	int e;

	r = fabs(r);
	if (r < 0x1p-1022)
		return 0x1p-1074;
	frexp(r, &e);
	return ldexp(1.0, e - 53);
}

static double ulp_f(double r)
{
	int e;

	r = fabs(r);
	if (r < 0x1p-126)
		return 0x1p-149;
	frexp(r, &e);
	return ldexp(1.0, e - 24);
}

static const double edges[] = {
	0.0, -0.0, 1.0, -1.0, 0.5, -0.5, 2.0, 10.0, 1000.0, 1e-300, -1e-300,
	5e-324, 2.2250738585072014e-308, 1.7976931348623157e308,
	-1.7976931348623157e308, INFINITY, -INFINITY, NAN, M_PI, M_PI_2,
	M_PI_4, -M_PI_2, 3 * M_PI_2, 1e22, 1e300, 0x1p20, 0x1p20 * M_PI_2,
	0x1p1023, 6381956970095103.0 * 0x1p797, 5.319372648326541e+255,
	709.782712893384, 709.79, -745.13321910194, -746, 0.9999999999999999,
	1.0000000000000002, 1e-8, 0.1, 0.3, 0.7, 3.0, 0.25, -2.5, 1e-20,
};

int main(int argc, char **argv)
{
	const char *f, *type, *dist;
	double lo, hi, maxu = 0, wx = 0, wy = 0, wg = 0, wr = 0;
	long n, i, bad = 0, cnt = 0;
	int isreal;

	if (argc != 8) {
		fprintf(stderr, "usage: FUNC TYPE DIST LO HI N SEED\n");
		return 2;
	}
	f = argv[1];
	type = argv[2];
	dist = argv[3];
	lo = atof(argv[4]);
	hi = atof(argv[5]);
	n = atol(argv[6]);
	rng = strtoull(argv[7], NULL, 0) * 0x9e3779b97f4a7c15ull + 1;
	isreal = !strcmp(type, "real");
	if (!strcmp(dist, "edge"))
		n = (long)(sizeof(edges) / sizeof(edges[0]));
	for (i = 0; i < n * (strcmp(dist, "edge") ? 1 : n); i++) {
		double x, y = 1.0, got, ref, err, u;

		if (!strcmp(dist, "edge")) {
			x = edges[i / n];
			y = edges[i % n];
		} else if (!strcmp(dist, "lin")) {
			x = lo + (hi - lo) * urand();
			y = lo + (hi - lo) * urand();
			if (!strcmp(f, "expt"))
				y = -60 + 120 * urand();
		} else {
			x = pow(10, lo + (hi - lo) * urand());
			y = pow(10, lo + (hi - lo) * urand());
			if (!strcmp(dist, "log")) {
				if (urand() < 0.5)
					x = -x;
				if (urand() < 0.5)
					y = -y;
			}
		}
		if (isreal) {
			x = (float)x;
			y = (float)y;
		}
#define ONE(name, libm)							\
		if (!strcmp(f, #name)) {				\
			ref = libm(x);					\
			got = isreal ? iec_##name##_real((float)x) :	\
				       iec_##name##_lreal(x);		\
		} else
		ONE(sqrt, sqrt) ONE(exp, exp) ONE(ln, log) ONE(log, log10)
		ONE(sin, sin) ONE(cos, cos) ONE(tan, tan) ONE(asin, asin)
		ONE(acos, acos) ONE(atan, atan)
		if (!strcmp(f, "atan2")) {
			ref = atan2(x, y);
			got = isreal ? iec_atan2_real((float)x, (float)y) :
				       iec_atan2_lreal(x, y);
		} else if (!strcmp(f, "expt")) {
			ref = pow(x, y);
			got = isreal ? iec_expt_real((float)x, (float)y) :
				       iec_expt_lreal(x, y);
		} else {
			fprintf(stderr, "unknown function %s\n", f);
			return 2;
		}
		cnt++;
		if (isreal && fabs(ref) > 3.4028234663852886e38 &&
		    !isinf(ref))
			ref = ref > 0 ? INFINITY : -INFINITY;
		if (isnan(ref) || isnan(got) || isinf(ref) || isinf(got)) {
			if (!(isnan(ref) && isnan(got)) &&
			    !(ref == got)) {
				/* REAL results that round to Inf/0 are fine */
				if (!(isreal && isinf(got) &&
				      fabs(ref) >= 3.4028235677973366e38)) {
					bad++;
					if (bad <= 3)
						fprintf(stderr,
							"mismatch %s(%a, %a): got %a ref %a\n",
							f, x, y, got, ref);
				}
			}
			continue;
		}
		u = isreal ? ulp_f(ref) : ulp_d(ref);
		err = fabs(got - ref) / u;
		if (err > maxu) {
			maxu = err;
			wx = x;
			wy = y;
			wg = got;
			wr = ref;
		}
	}
	printf("%.3f %a %a %a %a %ld %ld\n", maxu, wx, wy, wg, wr, bad, cnt);
	return 0;
}
