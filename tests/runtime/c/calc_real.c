/* SPDX-License-Identifier: GPL-2.0-only OR MIT */
/*
 * calc_real.c - driver for property tests of REAL/LREAL <-> STRING.
 *   d2s BITS  (LREAL as 16 hex digits)  -> the string
 *   f2s BITS  (REAL as 8 hex digits)    -> the string
 *   s2d TEXT  -> LREAL bits      s2f TEXT -> REAL bits
 */
#include <stdio.h>
#include <string.h>
#include "iec_real.h"

int main(void)
{
	char line[512], op[8], arg[400];
	static struct iec_string s;

	while (fgets(line, sizeof(line), stdin)) {
		if (sscanf(line, "%7s %399s", op, arg) != 2) {
			printf("ERR\n");
		} else if (!strcmp(op, "d2s") || !strcmp(op, "f2s")) {
			unsigned long long b = 0;
			double d;
			float f;
			unsigned int b32;

			sscanf(arg, "%llx", &b);
			if (op[0] == 'd') {
				memcpy(&d, &b, 8);
				iec_lreal_to_string(IEC_SB(s), d);
			} else {
				b32 = (unsigned int)b;
				memcpy(&f, &b32, 4);
				iec_real_to_string(IEC_SB(s), f);
			}
			printf("%.*s\n", (int)s.len, s.data);
		} else {
			struct iec_strv v = { arg, (iec_u16)strlen(arg) };

			if (!strcmp(op, "s2d")) {
				double d = iec_string_to_lreal(v);
				unsigned long long b;

				memcpy(&b, &d, 8);
				printf("%016llx\n", b);
			} else {
				float f = iec_string_to_real(v);
				unsigned int b;

				memcpy(&b, &f, 4);
				printf("%08x\n", b);
			}
		}
		fflush(stdout);
	}
	return 0;
}
