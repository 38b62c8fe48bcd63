/* SPDX-License-Identifier: GPL-2.0-only OR MIT */
/*
 * check.h - a tiny assertion harness for the runtime's C test drivers.
 * Each failed check prints file:line and the values; main() ends with
 * CHECK_DONE(), which prints "N passed, N failed" and sets the exit code.
 */
#ifndef IEC_TEST_CHECK_H
#define IEC_TEST_CHECK_H

#include <stdio.h>
#include <string.h>

static int check_passed, check_failed;

#define CHECK(cond)							\
	do {								\
		if (cond) {						\
			check_passed++;					\
		} else {						\
			check_failed++;					\
			printf("%s:%d: CHECK(%s) failed\n", __FILE__,	\
			       __LINE__, #cond);			\
		}							\
	} while (0)

#define CHECK_I(a, b)							\
	do {								\
		long long a_ = (long long)(a), b_ = (long long)(b);	\
		if (a_ == b_) {						\
			check_passed++;					\
		} else {						\
			check_failed++;					\
			printf("%s:%d: %s == %lld, expected %s == %lld\n", \
			       __FILE__, __LINE__, #a, a_, #b, b_);	\
		}							\
	} while (0)

#define CHECK_U(a, b)							\
	do {								\
		unsigned long long a_ = (unsigned long long)(a);	\
		unsigned long long b_ = (unsigned long long)(b);	\
		if (a_ == b_) {						\
			check_passed++;					\
		} else {						\
			check_failed++;					\
			printf("%s:%d: %s == %llu, expected %s == %llu\n", \
			       __FILE__, __LINE__, #a, a_, #b, b_);	\
		}							\
	} while (0)

/* Compare a runtime string (struct with len/data) against a C literal. */
#define CHECK_STR(s, lit)						\
	do {								\
		if ((s).len == sizeof(lit) - 1 &&			\
		    memcmp((s).data, (lit), sizeof(lit) - 1) == 0 &&	\
		    (s).data[(s).len] == 0) {				\
			check_passed++;					\
		} else {						\
			check_failed++;					\
			printf("%s:%d: %s == '%.*s' (len %u), expected '%s'\n", \
			       __FILE__, __LINE__, #s, (int)(s).len,	\
			       (s).data, (unsigned int)(s).len, lit);	\
		}							\
	} while (0)

#define CHECK_DONE()							\
	do {								\
		printf("%d passed, %d failed\n", check_passed,		\
		       check_failed);					\
		return check_failed ? 1 : 0;				\
	} while (0)

#endif /* IEC_TEST_CHECK_H */
