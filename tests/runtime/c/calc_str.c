/* SPDX-License-Identifier: GPL-2.0-only OR MIT */
/*
 * calc_str.c - line-oriented driver for property tests of the string
 * functions and string conversions.  Strings travel as hex ('-' = empty).
 *
 *   OP MODE CAP A B L P   (OP: left right mid concat insert delete replace)
 *     MODE: 0 destination separate, 1 destination is A, 2 destination is
 *     B, 3 destination is A and B is A too.  Prints the result in hex.
 *   find A B | cmp A B                     -> integer
 *   WOP ...  the same on WSTRING (w-prefixed op, chars as 4-hex-digit)
 *   s2i TYPE A -> integer   i2s TYPE VALUE -> hex string
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "iec_string.h"

#define CAPMAX 600

IEC_DECLARE_STRING(600);
IEC_DECLARE_WSTRING(600);

static unsigned int unhex(const char *h, char *out)
{
	unsigned int n = 0;

	if (strcmp(h, "-") == 0)
		return 0;
	while (h[0] && h[1]) {
		unsigned int v;

		sscanf(h, "%2x", &v);
		out[n++] = (char)v;
		h += 2;
	}
	return n;
}

static unsigned int unhexw(const char *h, iec_u16 *out)
{
	unsigned int n = 0;

	if (strcmp(h, "-") == 0)
		return 0;
	while (h[0] && h[1] && h[2] && h[3]) {
		unsigned int v;

		sscanf(h, "%4x", &v);
		out[n++] = (iec_u16)v;
		h += 4;
	}
	return n;
}

static void puthex(const char *p, unsigned int n)
{
	unsigned int i;

	if (!n)
		putchar('-');
	for (i = 0; i < n; i++)
		printf("%02x", (unsigned char)p[i]);
	putchar('\n');
}

static void puthexw(const iec_u16 *p, unsigned int n)
{
	unsigned int i;

	if (!n)
		putchar('-');
	for (i = 0; i < n; i++)
		printf("%04x", p[i]);
	putchar('\n');
}

/*
 * The destination is a STRING[600] whose capacity is narrowed to cap
 * through the strbuf; a canary after data[cap] proves nothing is written
 * past it.
 */
static void narrow_op(const char *op, int mode, unsigned int cap,
		      const char *ha, const char *hb, long long l,
		      long long p)
{
	static struct iec_string_600 d, a, b;
	struct iec_strbuf db;
	struct iec_strv va, vb;
	unsigned int i;

	memset(&d, 0x5a, sizeof(d));
	a.len = (iec_u16)unhex(ha, a.data);
	b.len = (iec_u16)unhex(hb, b.data);
	va = IEC_SV(a);
	vb = IEC_SV(b);
	if (mode == 1 || mode == 3) {
		/* the destination holds A (it must fit its capacity) */
		d.len = a.len;
		memcpy(d.data, a.data, a.len);
		va = iec_strv_make(d.data, d.len, (iec_u16)cap);
		if (mode == 3)
			vb = va;
	} else if (mode == 2) {
		d.len = b.len;
		memcpy(d.data, b.data, b.len);
		vb = iec_strv_make(d.data, d.len, (iec_u16)cap);
	}
	db.p = d.data;
	db.len = &d.len;
	db.cap = (iec_u16)cap;
	if (!strcmp(op, "left"))
		iec_left_string(db, va, l);
	else if (!strcmp(op, "right"))
		iec_right_string(db, va, l);
	else if (!strcmp(op, "mid"))
		iec_mid_string(db, va, l, p);
	else if (!strcmp(op, "concat"))
		iec_concat_string(db, va, vb);
	else if (!strcmp(op, "insert"))
		iec_insert_string(db, va, vb, p);
	else if (!strcmp(op, "delete"))
		iec_delete_string(db, va, l, p);
	else if (!strcmp(op, "replace"))
		iec_replace_string(db, va, vb, l, p);
	else if (!strcmp(op, "assign"))
		iec_assign_string(db, va);
	else {
		printf("ERR unknown op %s\n", op);
		return;
	}
	if (d.len > cap || d.data[d.len] != 0) {
		printf("ERR length/terminator\n");
		return;
	}
	for (i = cap + 1; i < sizeof(d.data); i++)
		if ((unsigned char)d.data[i] != 0x5a) {
			printf("ERR wrote past capacity\n");
			return;
		}
	puthex(d.data, d.len);
}

static void wide_op(const char *op, int mode, unsigned int cap,
		    const char *ha, const char *hb, long long l, long long p)
{
	static struct iec_wstring_600 d, a, b;
	struct iec_wstrbuf db;
	struct iec_wstrv va, vb;
	unsigned int i;

	memset(&d, 0x5a, sizeof(d));
	a.len = (iec_u16)unhexw(ha, a.data);
	b.len = (iec_u16)unhexw(hb, b.data);
	va = IEC_WSV(a);
	vb = IEC_WSV(b);
	if (mode == 1 || mode == 3) {
		d.len = a.len;
		memcpy(d.data, a.data, a.len * 2);
		va = iec_wstrv_make(d.data, d.len, (iec_u16)cap);
		if (mode == 3)
			vb = va;
	} else if (mode == 2) {
		d.len = b.len;
		memcpy(d.data, b.data, b.len * 2);
		vb = iec_wstrv_make(d.data, d.len, (iec_u16)cap);
	}
	db.p = d.data;
	db.len = &d.len;
	db.cap = (iec_u16)cap;
	if (!strcmp(op, "left"))
		iec_left_wstring(db, va, l);
	else if (!strcmp(op, "right"))
		iec_right_wstring(db, va, l);
	else if (!strcmp(op, "mid"))
		iec_mid_wstring(db, va, l, p);
	else if (!strcmp(op, "concat"))
		iec_concat_wstring(db, va, vb);
	else if (!strcmp(op, "insert"))
		iec_insert_wstring(db, va, vb, p);
	else if (!strcmp(op, "delete"))
		iec_delete_wstring(db, va, l, p);
	else if (!strcmp(op, "replace"))
		iec_replace_wstring(db, va, vb, l, p);
	else if (!strcmp(op, "assign"))
		iec_assign_wstring(db, va);
	else {
		printf("ERR unknown op %s\n", op);
		return;
	}
	if (d.len > cap || d.data[d.len] != 0) {
		printf("ERR length/terminator\n");
		return;
	}
	for (i = cap + 1; i < sizeof(d.data) / 2; i++)
		if (d.data[i] != 0x5a5a) {
			printf("ERR wrote past capacity\n");
			return;
		}
	puthexw(d.data, d.len);
}

#define S2I(n, fmt, cast)						\
	if (!strcmp(type, #n)) {					\
		printf(fmt "\n", (cast)iec_string_to_##n(v));		\
		return;							\
	}
#define I2S(n, T)							\
	if (!strcmp(type, #n)) {					\
		iec_##n##_to_string(IEC_SB(s), (T)val);			\
		puthex(s.data, s.len);					\
		return;							\
	}

static void conv(const char *cmd, const char *type, const char *arg)
{
	static struct iec_string s;
	char buf[CAPMAX];

	if (!strcmp(cmd, "s2i")) {
		struct iec_strv v = { buf, (iec_u16)unhex(arg, buf) };

		S2I(bool, "%d", int) S2I(sint, "%d", int) S2I(int, "%d", int)
		S2I(dint, "%d", int) S2I(lint, "%lld", long long)
		S2I(usint, "%u", unsigned int) S2I(uint, "%u", unsigned int)
		S2I(udint, "%u", unsigned int)
		S2I(ulint, "%llu", unsigned long long)
		S2I(byte, "%u", unsigned int) S2I(word, "%u", unsigned int)
		S2I(dword, "%u", unsigned int)
		S2I(lword, "%llu", unsigned long long)
		S2I(time, "%lld", long long) S2I(ltime, "%lld", long long)
		S2I(date, "%lld", long long) S2I(ldate, "%lld", long long)
		S2I(tod, "%lld", long long) S2I(ltod, "%lld", long long)
		S2I(dt, "%lld", long long) S2I(ldt, "%lld", long long)
	} else {
		unsigned long long val = strtoull(arg, NULL, 0);

		if (arg[0] == '-')
			val = (unsigned long long)strtoll(arg, NULL, 0);
		I2S(bool, iec_bool) I2S(sint, iec_sint) I2S(int, iec_int)
		I2S(dint, iec_dint) I2S(lint, iec_lint) I2S(usint, iec_usint)
		I2S(uint, iec_uint) I2S(udint, iec_udint) I2S(ulint, iec_ulint)
		I2S(byte, iec_byte) I2S(word, iec_word) I2S(dword, iec_dword)
		I2S(lword, iec_lword) I2S(time, iec_time) I2S(ltime, iec_ltime)
		I2S(date, iec_date) I2S(ldate, iec_ldate) I2S(tod, iec_tod)
		I2S(ltod, iec_ltod) I2S(dt, iec_dt) I2S(ldt, iec_ldt)
	}
	printf("ERR unknown type %s\n", type);
}

int main(void)
{
	char line[8192], op[32], a[4000], b[4000];
	int mode;
	unsigned int cap;
	long long l, p;

	while (fgets(line, sizeof(line), stdin)) {
		if (sscanf(line, "%31s", op) != 1)
			continue;
		if (!strcmp(op, "find") || !strcmp(op, "cmp") ||
		    !strcmp(op, "wfind") || !strcmp(op, "wcmp")) {
			static struct iec_string_600 x, y;
			static struct iec_wstring_600 wx, wy;
			bool wide = op[0] == 'w';

			sscanf(line, "%*s %3999s %3999s", a, b);
			if (wide) {
				wx.len = (iec_u16)unhexw(a, wx.data);
				wy.len = (iec_u16)unhexw(b, wy.data);
				printf("%d\n", !strcmp(op, "wfind") ?
				       iec_find_wstring(IEC_WSV(wx), IEC_WSV(wy)) :
				       iec_cmp_wstring(IEC_WSV(wx), IEC_WSV(wy)));
			} else {
				x.len = (iec_u16)unhex(a, x.data);
				y.len = (iec_u16)unhex(b, y.data);
				printf("%d\n", !strcmp(op, "find") ?
				       iec_find_string(IEC_SV(x), IEC_SV(y)) :
				       iec_cmp_string(IEC_SV(x), IEC_SV(y)));
			}
		} else if (!strcmp(op, "s2i") || !strcmp(op, "i2s")) {
			char type[32];

			if (sscanf(line, "%*s %31s %3999s", type, a) == 2)
				conv(op, type, a);
			else
				printf("ERR args\n");
		} else if (sscanf(line, "%*s %d %u %3999s %3999s %lld %lld",
				  &mode, &cap, a, b, &l, &p) == 6) {
			if (cap > CAPMAX)
				printf("ERR cap\n");
			else if (op[0] == 'w')
				wide_op(op + 1, mode, cap, a, b, l, p);
			else
				narrow_op(op, mode, cap, a, b, l, p);
		} else {
			printf("ERR parse\n");
		}
		fflush(stdout);
	}
	return 0;
}
