/* SPDX-License-Identifier: GPL-2.0-only OR MIT */
/*
 * iec_platform.h - the one place where the kernel and user space differ.
 *
 * Every other runtime header includes only this file (and other iec_*.h).
 * In the kernel (__KERNEL__ defined) it takes its types from <linux/types.h>;
 * in user space (host simulation and tests) it uses the freestanding headers
 * <stdint.h>, <stddef.h> and <stdbool.h> only: the runtime needs no libc.
 *
 * Memory helpers map onto the compiler builtins.  GCC may turn a builtin into
 * a call to memcpy/memmove/memset, which the kernel and libc both provide.
 */
#ifndef IEC_PLATFORM_H
#define IEC_PLATFORM_H

#ifdef __KERNEL__

#include <linux/types.h>
#include <linux/stddef.h>
#include <linux/compiler.h>

typedef s8 iec_s8;
typedef s16 iec_s16;
typedef s32 iec_s32;
typedef s64 iec_s64;
typedef u8 iec_u8;
typedef u16 iec_u16;
typedef u32 iec_u32;
typedef u64 iec_u64;
typedef size_t iec_size_t;

#else /* user space */

#include <stdint.h>
#include <stddef.h>
#include <stdbool.h>

typedef int8_t iec_s8;
typedef int16_t iec_s16;
typedef int32_t iec_s32;
typedef int64_t iec_s64;
typedef uint8_t iec_u8;
typedef uint16_t iec_u16;
typedef uint32_t iec_u32;
typedef uint64_t iec_u64;
typedef size_t iec_size_t;

#endif /* __KERNEL__ */

#define iec_likely(x)	__builtin_expect(!!(x), 1)
#define iec_unlikely(x)	__builtin_expect(!!(x), 0)

#define iec_memcpy(d, s, n)	__builtin_memcpy((d), (s), (n))
#define iec_memmove(d, s, n)	__builtin_memmove((d), (s), (n))
#define iec_memset(d, c, n)	__builtin_memset((d), (c), (n))

#define IEC_S8_MIN	(-128)
#define IEC_S8_MAX	127
#define IEC_S16_MIN	(-32768)
#define IEC_S16_MAX	32767
#define IEC_S32_MIN	(-2147483647 - 1)
#define IEC_S32_MAX	2147483647
#define IEC_S64_MIN	(-9223372036854775807LL - 1)
#define IEC_S64_MAX	9223372036854775807LL
#define IEC_U8_MAX	255U
#define IEC_U16_MAX	65535U
#define IEC_U32_MAX	4294967295U
#define IEC_U64_MAX	18446744073709551615ULL

#endif /* IEC_PLATFORM_H */
