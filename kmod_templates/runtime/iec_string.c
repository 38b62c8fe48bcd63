// SPDX-License-Identifier: GPL-2.0-only OR MIT
/*
 * iec_string.c - STRING/WSTRING functions and conversions (no floating
 * point, no libc).  Semantics are documented in iec_string.h.
 */
#include "iec_string.h"
#include "iec_conv.h"

/* ---------------------------------------------------------------------
 * Building a result from up to three pieces.
 *
 * A piece is a run of characters from an operand.  Operands may be the
 * destination itself (s := CONCAT(s, s)).  For every function here the
 * pieces are written in reverse order with memmove: a later piece never
 * lands on the old characters an earlier piece still has to read (either it
 * lands past the end of the old content, or the earlier piece was cut by
 * the capacity and the later one is then empty).  Truncation to the
 * capacity happens here and only here.
 */
struct iec__piece {
	const void *p;
	unsigned int n;
};

static void iec__assemble(void *dst, iec_u16 *dlen, unsigned int cap,
			  unsigned int esz, const struct iec__piece *pc,
			  int npc)
{
	unsigned int off[3], take[3], total = 0;
	char *d = dst;
	int i;

	for (i = 0; i < npc; i++) {
		unsigned int avail = cap - total;

		off[i] = total;
		take[i] = pc[i].n < avail ? pc[i].n : avail;
		total += take[i];
	}
	for (i = npc - 1; i >= 0; i--) {
		char *to = d + (iec_size_t)off[i] * esz;

		if (take[i] && to != (const char *)pc[i].p)
			iec_memmove(to, pc[i].p, (iec_size_t)take[i] * esz);
	}
	iec_memset(d + (iec_size_t)total * esz, 0, esz);
	*dlen = (iec_u16)total;
}

static unsigned int iec__clamp(iec_lint v, unsigned int hi)
{
	if (v <= 0)
		return 0;
	return (iec_u64)v >= hi ? hi : (unsigned int)v;
}

/* Generic bodies: p is the operand's first character, esz 1 or 2. */
static void g_assign(void *d, iec_u16 *dl, unsigned int cap, unsigned int esz,
		     const void *p, unsigned int n)
{
	struct iec__piece pc[1] = { { p, n } };

	iec__assemble(d, dl, cap, esz, pc, 1);
}

static void g_left(void *d, iec_u16 *dl, unsigned int cap, unsigned int esz,
		   const void *p, unsigned int n, iec_lint l)
{
	g_assign(d, dl, cap, esz, p, iec__clamp(l, n));
}

static void g_right(void *d, iec_u16 *dl, unsigned int cap, unsigned int esz,
		    const void *p, unsigned int n, iec_lint l)
{
	unsigned int k = iec__clamp(l, n);

	g_assign(d, dl, cap, esz, (const char *)p + (iec_size_t)(n - k) * esz,
		 k);
}

static void g_mid(void *d, iec_u16 *dl, unsigned int cap, unsigned int esz,
		  const void *p, unsigned int n, iec_lint l, iec_lint pos)
{
	unsigned int start, k;

	if (pos < 1 || (iec_u64)pos > n) {
		g_assign(d, dl, cap, esz, p, 0);
		return;
	}
	start = (unsigned int)pos - 1;
	k = iec__clamp(l, n - start);
	g_assign(d, dl, cap, esz, (const char *)p + (iec_size_t)start * esz,
		 k);
}

static void g_concat(void *d, iec_u16 *dl, unsigned int cap,
		     unsigned int esz, const void *p1, unsigned int n1,
		     const void *p2, unsigned int n2)
{
	struct iec__piece pc[2] = { { p1, n1 }, { p2, n2 } };

	iec__assemble(d, dl, cap, esz, pc, 2);
}

/* IN1[0..start) + IN2 + IN1[start+k..n1) */
static void g_splice(void *d, iec_u16 *dl, unsigned int cap,
		     unsigned int esz, const void *p1, unsigned int n1,
		     const void *p2, unsigned int n2, unsigned int start,
		     unsigned int k)
{
	struct iec__piece pc[3] = {
		{ p1, start },
		{ p2, n2 },
		{ (const char *)p1 + (iec_size_t)(start + k) * esz,
		  n1 - start - k },
	};

	iec__assemble(d, dl, cap, esz, pc, 3);
}

static void g_insert(void *d, iec_u16 *dl, unsigned int cap,
		     unsigned int esz, const void *p1, unsigned int n1,
		     const void *p2, unsigned int n2, iec_lint pos)
{
	g_splice(d, dl, cap, esz, p1, n1, p2, n2, iec__clamp(pos, n1), 0);
}

static void g_delete(void *d, iec_u16 *dl, unsigned int cap,
		     unsigned int esz, const void *p, unsigned int n,
		     iec_lint l, iec_lint pos)
{
	unsigned int start;

	if (pos < 1 || (iec_u64)pos > n) {
		g_assign(d, dl, cap, esz, p, n);
		return;
	}
	start = (unsigned int)pos - 1;
	g_splice(d, dl, cap, esz, p, n, p, 0, start,
		 iec__clamp(l, n - start));
}

static void g_replace(void *d, iec_u16 *dl, unsigned int cap,
		      unsigned int esz, const void *p1, unsigned int n1,
		      const void *p2, unsigned int n2, iec_lint l,
		      iec_lint pos)
{
	unsigned int start = pos <= 1 ? 0 : iec__clamp(pos - 1, n1);

	g_splice(d, dl, cap, esz, p1, n1, p2, n2, start,
		 iec__clamp(l, n1 - start));
}

static iec_dint g_find(unsigned int esz, const void *p1, unsigned int n1,
		       const void *p2, unsigned int n2)
{
	const char *a = p1, *b = p2;
	unsigned int i;

	if (n2 == 0 || n2 > n1)
		return 0;
	for (i = 0; i + n2 <= n1; i++) {
		if (__builtin_memcmp(a + (iec_size_t)i * esz, b,
				     (iec_size_t)n2 * esz) == 0)
			return (iec_dint)i + 1;
	}
	return 0;
}

/* ---------------------------------------------------------------------
 * STRING
 */
void iec_assign_string(struct iec_strbuf dst, struct iec_strv src)
{
	g_assign(dst.p, dst.len, dst.cap, 1, src.p, src.len);
}

void iec_left_string(struct iec_strbuf dst, struct iec_strv in, iec_lint l)
{
	g_left(dst.p, dst.len, dst.cap, 1, in.p, in.len, l);
}

void iec_right_string(struct iec_strbuf dst, struct iec_strv in, iec_lint l)
{
	g_right(dst.p, dst.len, dst.cap, 1, in.p, in.len, l);
}

void iec_mid_string(struct iec_strbuf dst, struct iec_strv in, iec_lint l,
		    iec_lint p)
{
	g_mid(dst.p, dst.len, dst.cap, 1, in.p, in.len, l, p);
}

void iec_concat_string(struct iec_strbuf dst, struct iec_strv in1,
		       struct iec_strv in2)
{
	g_concat(dst.p, dst.len, dst.cap, 1, in1.p, in1.len, in2.p, in2.len);
}

void iec_insert_string(struct iec_strbuf dst, struct iec_strv in1,
		       struct iec_strv in2, iec_lint p)
{
	g_insert(dst.p, dst.len, dst.cap, 1, in1.p, in1.len, in2.p, in2.len,
		 p);
}

void iec_delete_string(struct iec_strbuf dst, struct iec_strv in, iec_lint l,
		       iec_lint p)
{
	g_delete(dst.p, dst.len, dst.cap, 1, in.p, in.len, l, p);
}

void iec_replace_string(struct iec_strbuf dst, struct iec_strv in1,
			struct iec_strv in2, iec_lint l, iec_lint p)
{
	g_replace(dst.p, dst.len, dst.cap, 1, in1.p, in1.len, in2.p, in2.len,
		  l, p);
}

iec_dint iec_find_string(struct iec_strv in1, struct iec_strv in2)
{
	return g_find(1, in1.p, in1.len, in2.p, in2.len);
}

int iec_cmp_string(struct iec_strv a, struct iec_strv b)
{
	unsigned int i, n = a.len < b.len ? a.len : b.len;

	for (i = 0; i < n; i++) {
		unsigned char x = (unsigned char)a.p[i];
		unsigned char y = (unsigned char)b.p[i];

		if (x != y)
			return x < y ? -1 : 1;
	}
	return a.len == b.len ? 0 : (a.len < b.len ? -1 : 1);
}

/* ---------------------------------------------------------------------
 * WSTRING
 */
void iec_assign_wstring(struct iec_wstrbuf dst, struct iec_wstrv src)
{
	g_assign(dst.p, dst.len, dst.cap, 2, src.p, src.len);
}

void iec_left_wstring(struct iec_wstrbuf dst, struct iec_wstrv in,
		      iec_lint l)
{
	g_left(dst.p, dst.len, dst.cap, 2, in.p, in.len, l);
}

void iec_right_wstring(struct iec_wstrbuf dst, struct iec_wstrv in,
		       iec_lint l)
{
	g_right(dst.p, dst.len, dst.cap, 2, in.p, in.len, l);
}

void iec_mid_wstring(struct iec_wstrbuf dst, struct iec_wstrv in, iec_lint l,
		     iec_lint p)
{
	g_mid(dst.p, dst.len, dst.cap, 2, in.p, in.len, l, p);
}

void iec_concat_wstring(struct iec_wstrbuf dst, struct iec_wstrv in1,
			struct iec_wstrv in2)
{
	g_concat(dst.p, dst.len, dst.cap, 2, in1.p, in1.len, in2.p, in2.len);
}

void iec_insert_wstring(struct iec_wstrbuf dst, struct iec_wstrv in1,
			struct iec_wstrv in2, iec_lint p)
{
	g_insert(dst.p, dst.len, dst.cap, 2, in1.p, in1.len, in2.p, in2.len,
		 p);
}

void iec_delete_wstring(struct iec_wstrbuf dst, struct iec_wstrv in,
			iec_lint l, iec_lint p)
{
	g_delete(dst.p, dst.len, dst.cap, 2, in.p, in.len, l, p);
}

void iec_replace_wstring(struct iec_wstrbuf dst, struct iec_wstrv in1,
			 struct iec_wstrv in2, iec_lint l, iec_lint p)
{
	g_replace(dst.p, dst.len, dst.cap, 2, in1.p, in1.len, in2.p, in2.len,
		  l, p);
}

iec_dint iec_find_wstring(struct iec_wstrv in1, struct iec_wstrv in2)
{
	return g_find(2, in1.p, in1.len, in2.p, in2.len);
}

int iec_cmp_wstring(struct iec_wstrv a, struct iec_wstrv b)
{
	unsigned int i, n = a.len < b.len ? a.len : b.len;

	for (i = 0; i < n; i++) {
		if (a.p[i] != b.p[i])
			return a.p[i] < b.p[i] ? -1 : 1;
	}
	return a.len == b.len ? 0 : (a.len < b.len ? -1 : 1);
}

/* ---------------------------------------------------------------------
 * STRING <-> WSTRING, CHAR
 */
void iec_string_to_wstring(struct iec_wstrbuf dst, struct iec_strv src)
{
	unsigned int i, n = src.len < dst.cap ? src.len : dst.cap;

	for (i = 0; i < n; i++)
		dst.p[i] = (unsigned char)src.p[i];
	dst.p[n] = 0;
	*dst.len = (iec_u16)n;
}

void iec_wstring_to_string(struct iec_strbuf dst, struct iec_wstrv src)
{
	unsigned int i, n = src.len < dst.cap ? src.len : dst.cap;

	for (i = 0; i < n; i++)
		dst.p[i] = src.p[i] <= 255 ? (char)src.p[i] : '?';
	dst.p[n] = 0;
	*dst.len = (iec_u16)n;
}

void iec_char_to_string(struct iec_strbuf dst, iec_char c)
{
	char ch = (char)c;

	g_assign(dst.p, dst.len, dst.cap, 1, &ch, 1);
}

void iec_wchar_to_wstring(struct iec_wstrbuf dst, iec_wchar c)
{
	g_assign(dst.p, dst.len, dst.cap, 2, &c, 1);
}

iec_char iec_string_to_char(struct iec_strv s)
{
	return s.len ? (iec_char)s.p[0] : 0;
}

iec_wchar iec_wstring_to_wchar(struct iec_wstrv s)
{
	return s.len ? s.p[0] : 0;
}

void iec__store_chars(struct iec_strbuf dst, const char *p, unsigned int n)
{
	g_assign(dst.p, dst.len, dst.cap, 1, p, n);
}

void iec__store_wchars(struct iec_wstrbuf dst, const char *p, unsigned int n)
{
	unsigned int i;

	if (n > dst.cap)
		n = dst.cap;
	for (i = 0; i < n; i++)
		dst.p[i] = (unsigned char)p[i];
	dst.p[n] = 0;
	*dst.len = (iec_u16)n;
}

/*
 * Narrow a WSTRING for parsing: blanks at both ends are dropped; returns
 * the length, or 0 when the rest does not fit in buf (no literal is that
 * long) or holds a character above 127.
 */
unsigned int iec__narrow(char *buf, unsigned int size, const iec_u16 *p,
			 unsigned int len)
{
	unsigned int i, b = 0, e = len;

	while (b < e && (p[b] == ' ' || p[b] == '\t' || p[b] == '\r' ||
			 p[b] == '\n'))
		b++;
	while (e > b && (p[e - 1] == ' ' || p[e - 1] == '\t' ||
			 p[e - 1] == '\r' || p[e - 1] == '\n'))
		e--;
	if (e - b >= size)
		return 0;
	for (i = b; i < e; i++) {
		if (p[i] > 127)
			return 0;
		buf[i - b] = (char)p[i];
	}
	return e - b;
}

/* ---------------------------------------------------------------------
 * Formatting
 */
#define IEC__FMT_MAX 64

static unsigned int fmt_u64(char *buf, iec_u64 v)
{
	char tmp[20];
	unsigned int n = 0, i;

	do {
		tmp[n++] = (char)('0' + v % 10);
		v /= 10;
	} while (v);
	for (i = 0; i < n; i++)
		buf[i] = tmp[n - 1 - i];
	return n;
}

static unsigned int fmt_s64(char *buf, iec_s64 v)
{
	if (v < 0) {
		buf[0] = '-';
		return 1 + fmt_u64(buf + 1, (iec_u64)0 - (iec_u64)v);
	}
	return fmt_u64(buf, (iec_u64)v);
}

static unsigned int fmt_str(char *buf, const char *s)
{
	unsigned int n = 0;

	while (s[n]) {
		buf[n] = s[n];
		n++;
	}
	return n;
}

static unsigned int fmt_pad(char *buf, iec_u64 v, unsigned int width)
{
	char tmp[20];
	unsigned int n = fmt_u64(tmp, v), i = 0;

	while (n + i < width) {
		buf[i] = '0';
		i++;
	}
	iec_memcpy(buf + i, tmp, n);
	return i + n;
}

static unsigned int fmt_bool(char *buf, iec_bool v)
{
	return fmt_str(buf, v ? "TRUE" : "FALSE");
}

static unsigned int fmt_duration(char *buf, const char *prefix, iec_s64 v)
{
	static const struct {
		iec_s64 ns;
		const char *unit;
	} parts[] = {
		{ IEC_NS_PER_DAY, "d" }, { IEC_NS_PER_H, "h" },
		{ IEC_NS_PER_MIN, "m" }, { IEC_NS_PER_S, "s" },
		{ IEC_NS_PER_MS, "ms" }, { IEC_NS_PER_US, "us" },
		{ 1, "ns" },
	};
	unsigned int n = fmt_str(buf, prefix), i;
	iec_u64 mag = v < 0 ? (iec_u64)0 - (iec_u64)v : (iec_u64)v;

	if (v < 0)
		buf[n++] = '-';
	if (mag == 0)
		return n + fmt_str(buf + n, "0s");
	for (i = 0; i < sizeof(parts) / sizeof(parts[0]); i++) {
		iec_u64 q = mag / (iec_u64)parts[i].ns;

		if (q) {
			n += fmt_u64(buf + n, q);
			n += fmt_str(buf + n, parts[i].unit);
			mag -= q * (iec_u64)parts[i].ns;
		}
	}
	return n;
}

static unsigned int fmt_ymd(char *buf, iec_s64 v)
{
	iec_s64 y, m, d;
	unsigned int n = 0;

	iec__civil_from_days(iec__floordiv(v, IEC_NS_PER_DAY), &y, &m, &d);
	if (y < 0) {
		buf[n++] = '-';
		y = -y;
	}
	n += fmt_pad(buf + n, (iec_u64)y, 4);
	buf[n++] = '-';
	n += fmt_pad(buf + n, (iec_u64)m, 2);
	buf[n++] = '-';
	n += fmt_pad(buf + n, (iec_u64)d, 2);
	return n;
}

static unsigned int fmt_hms(char *buf, iec_s64 v)
{
	iec_u64 ns = (iec_u64)iec__floormod(v, IEC_NS_PER_DAY);
	iec_u64 frac = ns % IEC_NS_PER_S, secs = ns / IEC_NS_PER_S;
	unsigned int n = 0, digits = 9;

	n += fmt_pad(buf + n, secs / 3600, 2);
	buf[n++] = ':';
	n += fmt_pad(buf + n, secs / 60 % 60, 2);
	buf[n++] = ':';
	n += fmt_pad(buf + n, secs % 60, 2);
	if (frac) {
		while (frac % 10 == 0) {
			frac /= 10;
			digits--;
		}
		buf[n++] = '.';
		n += fmt_pad(buf + n, frac, digits);
	}
	return n;
}

static unsigned int fmt_date(char *buf, const char *prefix, iec_s64 v)
{
	unsigned int n = fmt_str(buf, prefix);

	return n + fmt_ymd(buf + n, v);
}

static unsigned int fmt_tod(char *buf, const char *prefix, iec_s64 v)
{
	unsigned int n = fmt_str(buf, prefix);

	return n + fmt_hms(buf + n, v);
}

static unsigned int fmt_dt(char *buf, const char *prefix, iec_s64 v)
{
	unsigned int n = fmt_date(buf, prefix, v);

	buf[n++] = '-';
	return n + fmt_hms(buf + n, v);
}

/* ---------------------------------------------------------------------
 * Parsing.  A cursor over a character range; blanks at both ends are
 * skipped by trim() before a parser starts.
 */
struct cur {
	const char *p;
	unsigned int i, n;
};

static bool is_blank(char c)
{
	return c == ' ' || c == '\t' || c == '\r' || c == '\n';
}

static bool is_digit(char c)
{
	return c >= '0' && c <= '9';
}

static char lower(char c)
{
	return (c >= 'A' && c <= 'Z') ? (char)(c - 'A' + 'a') : c;
}

static struct cur trim(const char *p, unsigned int n)
{
	struct cur c = { p, 0, n };

	while (c.i < c.n && is_blank(p[c.i]))
		c.i++;
	while (c.n > c.i && is_blank(p[c.n - 1]))
		c.n--;
	return c;
}

static bool at_end(const struct cur *c)
{
	return c->i >= c->n;
}

static char peek(const struct cur *c)
{
	return c->i < c->n ? c->p[c->i] : 0;
}

/* Skip one of the '#'-terminated prefixes in list (lower case, each ending
 * with '#'), case-insensitively.  Returns true if one was skipped. */
static bool skip_prefix(struct cur *c, const char *const *list)
{
	for (; *list; list++) {
		const char *w = *list;
		unsigned int k = 0;

		while (w[k] && c->i + k < c->n && lower(c->p[c->i + k]) == w[k])
			k++;
		if (!w[k]) {
			c->i += k;
			return true;
		}
	}
	return false;
}

static bool match_word(struct cur *c, const char *w)
{
	unsigned int k = 0;

	while (w[k] && c->i + k < c->n && lower(c->p[c->i + k]) == w[k])
		k++;
	if (w[k])
		return false;
	c->i += k;
	return true;
}

static int digit_value(char ch)
{
	ch = lower(ch);
	if (ch >= '0' && ch <= '9')
		return ch - '0';
	if (ch >= 'a' && ch <= 'f')
		return ch - 'a' + 10;
	return 99;
}

/*
 * Digits in base with '_' only between digits.  Sets *ovf on overflow of
 * 64 bits (the digits are still consumed).  Returns the number of digits.
 */
static unsigned int scan_digits(struct cur *c, unsigned int base,
				iec_u64 *val, bool *ovf)
{
	unsigned int nd = 0;
	iec_u64 v = 0;

	for (;;) {
		char ch = peek(c);
		int d = digit_value(ch);

		if (ch == '_' && nd && c->i + 1 < c->n &&
		    digit_value(c->p[c->i + 1]) < (int)base) {
			c->i++;
			continue;
		}
		if (d >= (int)base)
			break;
		if (v > (IEC_U64_MAX - (iec_u64)d) / base)
			*ovf = true;
		else
			v = v * base + (iec_u64)d;
		nd++;
		c->i++;
	}
	*val = v;
	return nd;
}

static const char *const int_prefixes[] = {
	"sint#", "int#", "dint#", "lint#", "usint#", "uint#", "udint#",
	"ulint#", "byte#", "word#", "dword#", "lword#", "bool#", NULL
};

/* Parse an integer literal; false if the text is not one. */
static bool parse_int(struct cur *c, bool *neg, iec_u64 *mag, bool *ovf)
{
	iec_u64 v;
	unsigned int base = 10;

	skip_prefix(c, int_prefixes);
	*neg = false;
	if (peek(c) == '+' || peek(c) == '-') {
		*neg = peek(c) == '-';
		c->i++;
	}
	if (!scan_digits(c, 10, &v, ovf))
		return false;
	if (peek(c) == '#') {
		if (*ovf || (v != 2 && v != 8 && v != 16))
			return false;
		base = (unsigned int)v;
		c->i++;
		if (!scan_digits(c, base, &v, ovf))
			return false;
	}
	*mag = v;
	return at_end(c);
}

/* Value of an integer string saturated to [lo, hi]; 0 if invalid. */
static iec_s64 str_to_signed(const char *p, unsigned int n, iec_s64 lo,
			     iec_s64 hi)
{
	struct cur c = trim(p, n);
	bool neg, ovf = false;
	iec_u64 mag;

	if (!parse_int(&c, &neg, &mag, &ovf))
		return 0;
	if (neg) {
		if (ovf || mag > (iec_u64)0 - (iec_u64)lo)
			return lo;
		return (iec_s64)((iec_u64)0 - mag);
	}
	if (ovf || mag > (iec_u64)hi)
		return hi;
	return (iec_s64)mag;
}

static iec_u64 str_to_unsigned(const char *p, unsigned int n, iec_u64 hi)
{
	struct cur c = trim(p, n);
	bool neg, ovf = false;
	iec_u64 mag;

	if (!parse_int(&c, &neg, &mag, &ovf))
		return 0;
	if (neg)
		return 0;
	if (ovf || mag > hi)
		return hi;
	return mag;
}

static iec_bool str_to_bool(const char *p, unsigned int n)
{
	struct cur c = trim(p, n);
	static const char *const pre[] = { "bool#", NULL };

	skip_prefix(&c, pre);
	if (match_word(&c, "true") && at_end(&c))
		return 1;
	c = trim(p, n);
	skip_prefix(&c, pre);
	if (match_word(&c, "false") && at_end(&c))
		return 0;
	return str_to_signed(p, n, IEC_S64_MIN, IEC_S64_MAX) != 0;
}

/* Fraction digits after '.', kept only while 10^k divides unit, so the
 * result is exact to the nanosecond; *ns gets fraction * unit. */
static bool scan_fraction(struct cur *c, iec_s64 unit, iec_u64 *ns)
{
	iec_u64 num = 0, scale = (iec_u64)unit;
	unsigned int nd = 0;

	while (is_digit(peek(c)) || (peek(c) == '_' && nd)) {
		char ch = c->p[c->i++];

		if (ch == '_')
			continue;
		nd++;
		/* digits below the nanosecond are dropped (truncation) */
		if (scale % 10 == 0) {
			scale /= 10;
			num = num * 10 + (iec_u64)(ch - '0');
		}
	}
	if (!nd)
		return false;
	*ns = num * scale;
	return true;
}

static const char *const time_prefixes[] = {
	"ltime#", "lt#", "time#", "t#", NULL
};

/* TIME literal body, e.g. 1d2h3m4s5ms, 1.5s, -250ms. */
static iec_s64 str_to_duration(const char *p, unsigned int n)
{
	static const struct {
		const char *unit;
		iec_s64 ns;
	} units[] = {
		{ "ms", IEC_NS_PER_MS }, { "us", IEC_NS_PER_US },
		{ "ns", 1 }, { "d", IEC_NS_PER_DAY }, { "h", IEC_NS_PER_H },
		{ "m", IEC_NS_PER_MIN }, { "s", IEC_NS_PER_S },
	};
	struct cur c = trim(p, n);
	iec_u64 total = 0;
	bool neg = false, any = false;

	skip_prefix(&c, time_prefixes);
	if (peek(&c) == '+' || peek(&c) == '-') {
		neg = peek(&c) == '-';
		c.i++;
	}
	while (!at_end(&c)) {
		iec_u64 v, frac = 0;
		bool ovf = false, has_frac = false;
		struct cur f;
		unsigned int u;

		if (!scan_digits(&c, 10, &v, &ovf))
			return 0;
		f = c;
		if (peek(&c) == '.') {
			has_frac = true;
			c.i++;
			f = c;
			while (is_digit(peek(&c)) || peek(&c) == '_')
				c.i++;
		}
		for (u = 0; u < sizeof(units) / sizeof(units[0]); u++)
			if (match_word(&c, units[u].unit))
				break;
		if (u == sizeof(units) / sizeof(units[0]))
			return 0;
		if (has_frac && !scan_fraction(&f, units[u].ns, &frac))
			return 0;
		if (peek(&c) == '_')
			c.i++;
		total += v * (iec_u64)units[u].ns + frac;
		any = true;
	}
	if (!any)
		return 0;
	return (iec_s64)(neg ? (iec_u64)0 - total : total);
}

static bool scan_num(struct cur *c, iec_u64 *v, unsigned int maxd)
{
	bool ovf = false;
	unsigned int nd = scan_digits(c, 10, v, &ovf);

	return nd > 0 && nd <= maxd && !ovf;
}

/* yyyy-mm-dd -> ns since 1970 */
static bool scan_ymd(struct cur *c, iec_s64 *out)
{
	static const unsigned char mdays[] = {
		31, 29, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31
	};
	iec_u64 y, m, d;
	iec_s64 days;

	if (!scan_num(c, &y, 4) || peek(c) != '-')
		return false;
	c->i++;
	if (!scan_num(c, &m, 2) || peek(c) != '-' || m < 1 || m > 12)
		return false;
	c->i++;
	if (!scan_num(c, &d, 2) || d < 1 || d > mdays[m - 1])
		return false;
	days = iec__days_from_civil((iec_s64)y, (iec_s64)m, (iec_s64)d);
	if (m == 2 && d == 29 &&
	    iec__days_from_civil((iec_s64)y, 3, 1) - days != 1)
		return false;
	*out = iec__wrap_mul(days, IEC_NS_PER_DAY);
	return true;
}

/* hh:mm:ss[.fff] -> ns since midnight */
static bool scan_hms(struct cur *c, iec_s64 *out)
{
	iec_u64 h, m, s, frac = 0;

	if (!scan_num(c, &h, 2) || peek(c) != ':' || h > 23)
		return false;
	c->i++;
	if (!scan_num(c, &m, 2) || peek(c) != ':' || m > 59)
		return false;
	c->i++;
	if (!scan_num(c, &s, 2) || s > 59)
		return false;
	if (peek(c) == '.') {
		c->i++;
		if (!scan_fraction(c, IEC_NS_PER_S, &frac))
			return false;
	}
	*out = (iec_s64)(h * IEC_NS_PER_H + m * IEC_NS_PER_MIN +
			 s * IEC_NS_PER_S + frac);
	return true;
}

static iec_s64 str_to_date(const char *p, unsigned int n)
{
	static const char *const pre[] = {
		"ldate#", "ld#", "date#", "d#", NULL
	};
	struct cur c = trim(p, n);
	iec_s64 v;

	skip_prefix(&c, pre);
	if (!scan_ymd(&c, &v) || !at_end(&c))
		return 0;
	return v;
}

static iec_s64 str_to_tod(const char *p, unsigned int n)
{
	static const char *const pre[] = {
		"ltime_of_day#", "ltod#", "time_of_day#", "tod#", NULL
	};
	struct cur c = trim(p, n);
	iec_s64 v;

	skip_prefix(&c, pre);
	if (!scan_hms(&c, &v) || !at_end(&c))
		return 0;
	return v;
}

static iec_s64 str_to_dt(const char *p, unsigned int n)
{
	static const char *const pre[] = {
		"ldate_and_time#", "ldt#", "date_and_time#", "dt#", NULL
	};
	struct cur c = trim(p, n);
	iec_s64 d, t;

	skip_prefix(&c, pre);
	if (!scan_ymd(&c, &d) || peek(&c) != '-')
		return 0;
	c.i++;
	if (!scan_hms(&c, &t) || !at_end(&c))
		return 0;
	return iec__wrap_add(d, t);
}

/* ---------------------------------------------------------------------
 * The conversion functions.  FMT formats v into buf, PARSE(p, n) turns a
 * character range into a value.
 */
#define IEC__DEF_STR_CONV(n, T, FMT, PARSE)				\
void iec_##n##_to_string(struct iec_strbuf dst, T v)			\
{									\
	char buf[IEC__FMT_MAX];						\
									\
	iec__store_chars(dst, buf, FMT);				\
}									\
void iec_##n##_to_wstring(struct iec_wstrbuf dst, T v)			\
{									\
	char buf[IEC__FMT_MAX];						\
									\
	iec__store_wchars(dst, buf, FMT);				\
}									\
T iec_string_to_##n(struct iec_strv s)					\
{									\
	const char *p = s.p;						\
	unsigned int len = s.len;					\
									\
	return (T)(PARSE);						\
}									\
T iec_wstring_to_##n(struct iec_wstrv s)				\
{									\
	char buf[IEC__FMT_MAX * 2];					\
	const char *p = buf;						\
	unsigned int len = iec__narrow(buf, sizeof(buf), s.p, s.len);	\
									\
	return (T)(PARSE);						\
}

#define IEC__SIGNED(n, T, lo, hi)					\
	IEC__DEF_STR_CONV(n, T, fmt_s64(buf, v), str_to_signed(p, len, lo, hi))
#define IEC__UNSIGNED(n, T, hi)						\
	IEC__DEF_STR_CONV(n, T, fmt_u64(buf, v), str_to_unsigned(p, len, hi))

IEC__DEF_STR_CONV(bool, iec_bool, fmt_bool(buf, v), str_to_bool(p, len))
IEC__SIGNED(sint, iec_sint, IEC_S8_MIN, IEC_S8_MAX)
IEC__SIGNED(int, iec_int, IEC_S16_MIN, IEC_S16_MAX)
IEC__SIGNED(dint, iec_dint, IEC_S32_MIN, IEC_S32_MAX)
IEC__SIGNED(lint, iec_lint, IEC_S64_MIN, IEC_S64_MAX)
IEC__UNSIGNED(usint, iec_usint, IEC_U8_MAX)
IEC__UNSIGNED(uint, iec_uint, IEC_U16_MAX)
IEC__UNSIGNED(udint, iec_udint, IEC_U32_MAX)
IEC__UNSIGNED(ulint, iec_ulint, IEC_U64_MAX)
IEC__UNSIGNED(byte, iec_byte, IEC_U8_MAX)
IEC__UNSIGNED(word, iec_word, IEC_U16_MAX)
IEC__UNSIGNED(dword, iec_dword, IEC_U32_MAX)
IEC__UNSIGNED(lword, iec_lword, IEC_U64_MAX)
IEC__DEF_STR_CONV(time, iec_time, fmt_duration(buf, "T#", v),
		  str_to_duration(p, len))
IEC__DEF_STR_CONV(ltime, iec_ltime, fmt_duration(buf, "LTIME#", v),
		  str_to_duration(p, len))
IEC__DEF_STR_CONV(date, iec_date, fmt_date(buf, "D#", v), str_to_date(p, len))
IEC__DEF_STR_CONV(ldate, iec_ldate, fmt_date(buf, "LDATE#", v),
		  str_to_date(p, len))
IEC__DEF_STR_CONV(tod, iec_tod, fmt_tod(buf, "TOD#", v), str_to_tod(p, len))
IEC__DEF_STR_CONV(ltod, iec_ltod, fmt_tod(buf, "LTOD#", v),
		  str_to_tod(p, len))
IEC__DEF_STR_CONV(dt, iec_dt, fmt_dt(buf, "DT#", v), str_to_dt(p, len))
IEC__DEF_STR_CONV(ldt, iec_ldt, fmt_dt(buf, "LDT#", v), str_to_dt(p, len))
