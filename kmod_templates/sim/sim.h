/* SPDX-License-Identifier: GPL-2.0-only OR MIT */
/*
 * sim.h - the tables a generated configuration gives the host simulator.
 */
#ifndef IEC_SIM_H
#define IEC_SIM_H

#include "iec_gen.h"

struct sim_var {
	const char *path;	/* IEC path: level, r1.p1.count, %IX0.0 */
	void *addr;
	char kind;		/* b i u f t e s w */
	unsigned char size;	/* bytes of a scalar */
};

struct sim_task {
	const char *name;	/* resource.task */
	long long interval_ns;	/* 0: an event task */
	int priority;		/* IEC: 0 is the most urgent */
	const iec_bool *single;	/* SINGLE variable of an event task */
	void (*run)(struct iec_ctx *ctx);
	unsigned int loop_budget;	/* iterations per cycle, as in the kernel */
	long long watchdog_ns;		/* 0: no limit */
	unsigned int watchdog_overruns;	/* overrunning cycles in a row; 0: no limit */
};

struct sim_pou_file {
	const char *pou;
	const char *path;
};

extern const struct sim_var sim_vars[];
extern const int sim_nvars;
extern const struct sim_task sim_tasks[];
extern const int sim_ntasks;
extern const struct sim_pou_file sim_pou_files[];
extern const int sim_npou_files;
void sim_init(void);
/* the globals before a task cycle, put back when the cycle faults */
void sim_globals_save(void);
void sim_globals_restore(void);
/* the IEC path of a pointer member left NULL by sim_init(), or NULL */
const char *sim_unbound_pointer(void);

#endif /* IEC_SIM_H */
