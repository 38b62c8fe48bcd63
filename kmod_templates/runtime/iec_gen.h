/* SPDX-License-Identifier: GPL-2.0-only OR MIT */
/*
 * iec_gen.h - what generated POU code needs beyond the runtime library.
 *
 * IEC_POU_SCOPE: storage class of POU functions.  Program-type modules keep
 * every POU function static (the GFT slot is their only way in), so two
 * versions of a program type can be loaded side by side; the host
 * simulation defines it empty to export the bodies.
 */
#ifndef IEC_GEN_H
#define IEC_GEN_H

#include "iec_types.h"
#include "iec_fault.h"
#include "iec_int.h"
#include "iec_conv.h"
#include "iec_time.h"
#include "iec_string.h"
#include "iec_std_fb.h"
#include "iec_real.h"

#ifndef IEC_POU_SCOPE
#define IEC_POU_SCOPE static
#endif

/* Views and destinations of fixed-length string variables. */
#define IEC_STRV(s)							\
	iec_strv_make((s).data, (s).len, (iec_u16)(sizeof((s).data) - 1))
#define IEC_STRBUF(s)							\
	((struct iec_strbuf){ .p = (s).data, .len = &(s).len,		\
			      .cap = (iec_u16)(sizeof((s).data) - 1) })
#define IEC_WSTRV(s)							\
	iec_wstrv_make((s).data, (s).len,				\
		       (iec_u16)(sizeof((s).data) / sizeof((s).data[0]) - 1))
#define IEC_WSTRBUF(s)							\
	((struct iec_wstrbuf){ .p = (s).data, .len = &(s).len,		\
			       .cap = (iec_u16)(sizeof((s).data) /		\
						sizeof((s).data[0]) - 1) })

#endif /* IEC_GEN_H */
