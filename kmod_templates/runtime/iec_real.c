// SPDX-License-Identifier: GPL-2.0-only OR MIT
/*
 * iec_real.c - REAL/LREAL <-> STRING/WSTRING (floating-point object).
 *
 * Formatting finds the shortest decimal (1..9 digits for REAL, 1..17 for
 * LREAL) that reads back as the same value; reading multiplies the decimal
 * significand by a power of ten in double-double arithmetic and rounds
 * once.  Both are exact except in rare halfway cases beyond the
 * double-double precision (about 2^-100).
 */
#include "iec_real.h"
#include "iec_dd.h"

/* x * 10^k, in steps that neither overflow nor underflow too early. */
static struct iec__dd pow10_dd(int k)
{
	struct iec__dd r = { 1.0, 0 }, p = { 10.0, 0 };

	while (k) {
		if (k & 1)
			r = iec__dd_mul(r, p);
		k >>= 1;
		if (k)
			p = iec__dd_mul(p, p);
	}
	return r;
}

static struct iec__dd scale10(struct iec__dd x, int k)
{
	struct iec__dd big = pow10_dd(256);

	while (k > 256) {
		x = iec__dd_mul(x, big);
		k -= 256;
	}
	while (k < -256) {
		x = iec__dd_div(x, big);
		k += 256;
	}
	if (k >= 0)
		return iec__dd_mul(x, pow10_dd(k));
	return iec__dd_div(x, pow10_dd(-k));
}

static struct iec__dd u64_dd(iec_u64 n)
{
	double hi = (double)n;
	iec_s64 rest = (iec_s64)(n - (iec_u64)hi);	/* |rest| < 2^11 */

	return iec__fast_two_sum(hi, (double)rest);
}

/*
 * v (> 0, scaled by 2^64) rounded to the grid the unscaled result has:
 * the double grid, or 2^-1074 (2^-1010 scaled) once it is subnormal, in
 * one rounding, ties to even.
 */
static double subnormal_round(struct iec__dd v)
{
	const double c = 0x1p-958, grid = 0x1p-1010;
	double q, err;

	if (v.hi >= c)
		return v.hi + v.lo;
	q = v.hi + c;			/* v.hi rounded to the grid, + c */
	err = (v.hi - (q - c)) + v.lo;	/* what is left, in [-grid, grid] */
	q -= c;
	if (err > grid / 2 || (err == grid / 2 &&
			       ((iec_u64)(q / grid) & 1)))
		q += grid;
	else if (err < -grid / 2 || (err == -grid / 2 &&
				     ((iec_u64)(q / grid) & 1)))
		q -= grid;
	return q;
}

/* n * 10^k rounded to double */
static double decimal_to_double(iec_u64 n, int k)
{
	struct iec__dd v;

	if (n == 0)
		return 0.0;
	if (k > 400)
		return IEC__INF_D;
	if (k < -400)
		k = -400;	/* n < 2^64: the result is 0 anyway */
	if (k > 280) {
		/* keep the products away from overflow: work 2^-64 lower */
		v = scale10(iec__dd_mul_d(u64_dd(n), 0x1p-64), k);
		v.hi = (v.hi + v.lo) * 0x1p64;
		return v.hi != v.hi ? IEC__INF_D : v.hi;
	}
	if (k < -280) {
		/* keep the low part out of the subnormal range: 2^64 higher */
		v = scale10(iec__dd_mul_d(u64_dd(n), 0x1p64), k);
		return subnormal_round(v) * 0x1p-64;
	}
	v = scale10(u64_dd(n), k);
	return v.hi + v.lo;
}

/* round(a * 10^k) for 0 < a * 10^k < 2^62 */
static iec_u64 round_scaled(double a, int k)
{
	struct iec__dd x;
	double r, d, dl;
	iec_u64 n;

	if (a > 0x1p960) {
		/* keep the products away from overflow: work 2^-64 lower */
		x = scale10((struct iec__dd){ a * 0x1p-64, 0 }, k);
		x.hi *= 0x1p64;
		x.lo *= 0x1p64;
	} else {
		x = scale10((struct iec__dd){ a, 0 }, k);
	}
	/* x.hi may be above 2^53 (ulp > 1): round hi, then the rest */
	r = iec__rint(x.hi);
	d = (x.hi - r) + x.lo;
	dl = iec__rint(d);
	n = (iec_u64)((iec_s64)r + (iec_s64)dl);
	d -= dl;			/* in [-0.5, 0.5] */
	if (n & 1) {			/* ties to even */
		if (d == 0.5)
			n++;
		else if (d == -0.5)
			n--;
	}
	return n;
}

static const iec_u64 POW10_U64[20] = {
	1ull, 10ull, 100ull, 1000ull, 10000ull, 100000ull, 1000000ull,
	10000000ull, 100000000ull, 1000000000ull, 10000000000ull,
	100000000000ull, 1000000000000ull, 10000000000000ull,
	100000000000000ull, 1000000000000000ull, 10000000000000000ull,
	100000000000000000ull, 1000000000000000000ull,
	10000000000000000000ull,
};

static unsigned int put_str(char *buf, const char *s)
{
	unsigned int n = 0;

	while (s[n]) {
		buf[n] = s[n];
		n++;
	}
	return n;
}

static int reads_back(iec_u64 n, int k, double a, int is_real)
{
	double v = decimal_to_double(n, k);

	if (is_real)
		return iec_lreal_to_real(v) == (float)a;
	return v == a;
}

/*
 * Shortest round-trip decimal of a (finite, > 0).  Returns the digits in
 * *digits (p of them) and the decimal exponent of the first digit.
 */
static int shortest(double a, int is_real, iec_u64 *digits, int *ndig)
{
	int e2, e10, p, maxp = is_real ? 9 : 17, tries;
	iec_u64 n = 0;

	e2 = (int)((iec__asu64(a) >> 52) & 0x7ff) - 1023;
	if (e2 == -1023)			/* subnormal */
		e2 = -1074 + 63 - __builtin_clzll(iec__asu64(a));
	e10 = (int)((double)e2 * 0.30102999566398120);
	if (e2 < 0)
		e10--;
	for (p = 1; p <= maxp; p++) {
		for (tries = 0; tries < 4; tries++) {
			n = round_scaled(a, p - 1 - e10);
			if (n >= POW10_U64[p])
				e10++;
			else if (n < POW10_U64[p - 1])
				e10--;
			else
				break;
		}
		/* the nearest p-digit decimal, else a neighbour (a tie that
		 * rounded to even may not read back) */
		if (reads_back(n, e10 - p + 1, a, is_real))
			break;
		if (reads_back(n + 1, e10 - p + 1, a, is_real) &&
		    n + 1 < POW10_U64[p]) {
			n++;
			break;
		}
		if (reads_back(n - 1, e10 - p + 1, a, is_real) &&
		    n - 1 >= POW10_U64[p - 1]) {
			n--;
			break;
		}
	}
	if (p > maxp)
		p = maxp;
	*digits = n;
	*ndig = p;
	return e10;
}

static unsigned int fmt_real(char *buf, double v, int is_real)
{
	char dig[20];
	iec_u64 n;
	int p, e10, i, plain_max = is_real ? 7 : 15;
	unsigned int len = 0;

	if (v != v)
		return put_str(buf, "NaN");
	if (iec__asu64(v) >> 63) {
		buf[len++] = '-';
		v = -v;
	}
	if (v == IEC__INF_D)
		return len + put_str(buf + len, "Inf");
	if (v == 0)
		return len + put_str(buf + len, "0.0");
	e10 = shortest(v, is_real, &n, &p);
	for (i = p - 1; i >= 0; i--) {
		dig[i] = (char)('0' + n % 10);
		n /= 10;
	}
	if (e10 >= -5 && e10 < plain_max) {
		if (e10 < 0) {
			len += put_str(buf + len, "0.");
			for (i = -1; i > e10; i--)
				buf[len++] = '0';
			for (i = 0; i < p; i++)
				buf[len++] = dig[i];
			return len;
		}
		for (i = 0; i <= e10; i++)
			buf[len++] = i < p ? dig[i] : '0';
		buf[len++] = '.';
		if (p <= e10 + 1)
			buf[len++] = '0';
		for (i = e10 + 1; i < p; i++)
			buf[len++] = dig[i];
		return len;
	}
	buf[len++] = dig[0];
	buf[len++] = '.';
	if (p == 1)
		buf[len++] = '0';
	for (i = 1; i < p; i++)
		buf[len++] = dig[i];
	buf[len++] = 'E';
	buf[len++] = e10 < 0 ? '-' : '+';
	if (e10 < 0)
		e10 = -e10;
	if (e10 >= 100)
		buf[len++] = (char)('0' + e10 / 100);
	if (e10 >= 10)
		buf[len++] = (char)('0' + e10 / 10 % 10);
	buf[len++] = (char)('0' + e10 % 10);
	return len;
}

/* ---------------------------------------------------------------------
 * Parsing
 */
static char lower(char c)
{
	return (c >= 'A' && c <= 'Z') ? (char)(c - 'A' + 'a') : c;
}

static int is_blank(char c)
{
	return c == ' ' || c == '\t' || c == '\r' || c == '\n';
}

static int match(const char *p, unsigned int n, unsigned int *i,
		 const char *w)
{
	unsigned int k = 0;

	while (w[k] && *i + k < n && lower(p[*i + k]) == w[k])
		k++;
	if (w[k])
		return 0;
	*i += k;
	return 1;
}

static int is_digit(char c)
{
	return c >= '0' && c <= '9';
}

/* Digits with '_' between them; appends to the significand. */
static unsigned int scan(const char *p, unsigned int n, unsigned int *i,
			 iec_u64 *sig, int *nsig, int *drop)
{
	unsigned int nd = 0;

	while (*i < n) {
		char c = p[*i];

		if (c == '_' && nd && *i + 1 < n && is_digit(p[*i + 1])) {
			(*i)++;
			continue;
		}
		if (!is_digit(c))
			break;
		if (*nsig < 19) {
			*sig = *sig * 10 + (iec_u64)(c - '0');
			if (*sig)
				(*nsig)++;
		} else {
			(*drop)++;
		}
		nd++;
		(*i)++;
	}
	return nd;
}

static double parse_real(const char *p, unsigned int n)
{
	unsigned int i = 0, nd;
	iec_u64 sig = 0, ex = 0;
	int nsig = 0, drop = 0, fracdig = 0, eneg = 0, neg = 0, dummy = 0;
	double v;

	while (i < n && is_blank(p[i]))
		i++;
	while (n > i && is_blank(p[n - 1]))
		n--;
	if (!match(p, n, &i, "lreal#"))
		match(p, n, &i, "real#");
	if (i < n && (p[i] == '+' || p[i] == '-'))
		neg = p[i++] == '-';
	if (match(p, n, &i, "nan"))
		return i == n ? IEC__NAN_D : 0.0;
	if (match(p, n, &i, "inf")) {
		match(p, n, &i, "inity");
		if (i != n)
			return 0.0;
		return neg ? -IEC__INF_D : IEC__INF_D;
	}
	if (!scan(p, n, &i, &sig, &nsig, &drop))
		return 0.0;
	if (i < n && p[i] == '.') {
		int before = drop;

		i++;
		nd = scan(p, n, &i, &sig, &nsig, &drop);
		if (!nd)
			return 0.0;
		/* fraction digits kept lower the exponent, dropped ones not */
		fracdig = (int)nd - (drop - before);
		drop = before;
	}
	if (i < n && (p[i] == 'e' || p[i] == 'E')) {
		iec_u64 e = 0;
		int ne = 0;

		i++;
		if (i < n && (p[i] == '+' || p[i] == '-'))
			eneg = p[i++] == '-';
		if (!scan(p, n, &i, &e, &ne, &dummy))
			return 0.0;
		ex = e > 100000 || dummy ? 100000 : e;
	}
	if (i != n)
		return 0.0;
	v = decimal_to_double(sig, (eneg ? -(int)ex : (int)ex) + drop -
			      fracdig);
	return neg ? -v : v;
}

/* ---------------------------------------------------------------------
 * The conversion functions
 */
#define IEC__REAL_FMT_MAX 40

void iec_real_to_string(struct iec_strbuf dst, iec_real v)
{
	char buf[IEC__REAL_FMT_MAX];

	iec__store_chars(dst, buf, fmt_real(buf, v, 1));
}

void iec_lreal_to_string(struct iec_strbuf dst, iec_lreal v)
{
	char buf[IEC__REAL_FMT_MAX];

	iec__store_chars(dst, buf, fmt_real(buf, v, 0));
}

void iec_real_to_wstring(struct iec_wstrbuf dst, iec_real v)
{
	char buf[IEC__REAL_FMT_MAX];

	iec__store_wchars(dst, buf, fmt_real(buf, v, 1));
}

void iec_lreal_to_wstring(struct iec_wstrbuf dst, iec_lreal v)
{
	char buf[IEC__REAL_FMT_MAX];

	iec__store_wchars(dst, buf, fmt_real(buf, v, 0));
}

iec_lreal iec_string_to_lreal(struct iec_strv s)
{
	return parse_real(s.p, s.len);
}

iec_real iec_string_to_real(struct iec_strv s)
{
	return iec_lreal_to_real(parse_real(s.p, s.len));
}

iec_lreal iec_wstring_to_lreal(struct iec_wstrv s)
{
	char buf[128];
	unsigned int n = iec__narrow(buf, sizeof(buf), s.p, s.len);

	return parse_real(buf, n);
}

iec_real iec_wstring_to_real(struct iec_wstrv s)
{
	return iec_lreal_to_real(iec_wstring_to_lreal(s));
}
