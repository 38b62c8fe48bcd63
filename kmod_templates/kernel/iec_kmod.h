/* SPDX-License-Identifier: GPL-2.0-only OR MIT */
/*
 * iec_kmod.h - the interface between the modules of one IEC configuration.
 *
 *   configuration module  the global image, the process image, the GFT,
 *                         the lock that makes copy-in/copy-out atomic,
 *                         sysfs and generic netlink (iec_config_rt.c,
 *                         iec_ctl.c, iec_ctl_nl.c, iec_ctl_sysfs.c,
 *                         iec_vars.c); exports the iec2kmod_*
 *                         functions
 *   resource module       program instances (their state), the resource's
 *                         globals, one kthread per TASK (iec_resource_rt.c)
 *   program-type module   the body of one program type and everything it
 *                         calls; publishes it into its GFT slot on insert
 *
 * The exported names are fixed, so a second configuration module cannot be
 * loaded next to the first: one configuration at a time.
 */
#ifndef IEC_KMOD_H
#define IEC_KMOD_H

#include <linux/types.h>
#include <linux/hrtimer.h>
#include <linux/ktime.h>
#include <linux/list.h>
#include <linux/log2.h>
#include <linux/module.h>
#include <linux/rcupdate.h>
#include <linux/spinlock.h>

#include "iec_fault.h"

#define IEC_KMOD_ABI		2
/*
 * Release latency histogram, log-linear so that it covers the worst case
 * and stays precise where most samples are: buckets 0..31 are 1 us wide
 * ([b, b + 1) us); from 32 us on, four buckets per octave: bucket
 * 32 + 4 * o + s holds [(32 << o) * (4 + s) / 4, (32 << o) * (5 + s) / 4) us
 * (o = 0..7); the last bucket counts everything from 7168 us on (overflow).
 * benchmarks/jitter.py decodes it (iec_hist_bucket()).
 */
#define IEC_HIST_BUCKETS	64
#define IEC_POU_NAME_LEN	64
#define IEC_START_DELAY_MS	50	/* start command to the first release */

/* What the kernel checks in a value written or forced (iec_var_desc.check) */
enum iec_value_check {
	IEC_VCHK_NONE = 0,
	IEC_VCHK_RANGE,		/* a subrange: range.s (kind i) or range.u (kind u) */
	IEC_VCHK_ENUM,		/* an enumeration: one of enum_values[] */
};

/*
 * One variable the manager can read and write by its IEC path.  Generated
 * from the checked project (iec2kmod/kmod, the vars[] tables of
 * config_main.c.j2 and resource_main.c.j2): the kernel refuses by itself
 * what does not fit the declaration (iec_vars.c, iec_value_check()).
 */
struct iec_var_desc {
	const char *path;
	void *addr;
	u32 size;		/* bytes of the C object */
	char kind;		/* b i u f t e s w (see codegen/plan.py) */
	/* 0: read-only (CONSTANT, an FB output, an SFC step): no write, no force */
	u8 writable;
	u16 single_event;	/* 1 + event number if it is a SINGLE variable */
	/* 1 + index in its resource's tasks[] of the task that runs the
	 * program instance owning it; 0: a global (image lock) */
	u16 task;
	u8 check;		/* enum iec_value_check */
	u32 cap;		/* kind s/w: the declared capacity n of STRING[n] */
	union {
		struct { s64 lo, hi; } s;
		struct { u64 lo, hi; } u;
	} range;		/* IEC_VCHK_RANGE, bounds included */
	/* IEC_VCHK_ENUM: the values, as the C object holds them sign-extended */
	const s64 *enum_values;
	u32 nenum;
};

/* A program type's body, published into its GFT slot. */
struct iec_program_type {
	const char *type_name;
	const char *build_id;	/* identifies this build of the module */
	u64 iface_hash;		/* layout of the instance state */
	void (*body)(void *self, struct iec_ctx *ctx);
	bool uses_fpu;
	struct module *owner;
	/* configuration module: next in its slot's list of retired bodies */
	struct iec_program_type *retired_next;
	/* CLOCK_REALTIME of the first cycle that ran this body, 0 before */
	u64 first_run_ns;
	/* 1 + task_id of the task whose cycle that was, 0 before */
	u32 first_run_task;
};

struct iec_gft_slot {
	const char *type_name;
	u64 iface_hash;
	struct iec_program_type __rcu *cur;
	/*
	 * Bodies replaced while a task was inside a cycle that did not end
	 * within the bound: their modules keep the slot's reference until a
	 * later grace period succeeds (iec_gft_sync()).
	 */
	struct iec_program_type *retired;
	/*
	 * A new build inserted with stage=1 (its module reference held): it
	 * is published by IEC_CMD_SLOT_PUBLISH, the quick half of a swap.
	 */
	struct iec_program_type *staged;
	ktime_t since;		/* CLOCK_REALTIME of the last publication */
	u64 publications;
};

enum iec_task_state {
	IEC_TASK_STOPPED = 0,
	IEC_TASK_RUNNING,
	IEC_TASK_FAULT,
};

struct iec_task_stats {
	u64 cycles;
	u64 overruns;		/* releases missed because a cycle ran late */
	u64 faults;
	s64 exec_min_ns;
	s64 exec_max_ns;
	s64 exec_sum_ns;
	s64 latency_max_ns;	/* release jitter: wake-up minus deadline */
	s64 latency_sum_ns;
	u64 hist[IEC_HIST_BUCKETS];	/* latency, see IEC_HIST_BUCKETS */
	u64 starts;		/* since the load; more than one: restarted */
	ktime_t started;	/* CLOCK_REALTIME of the last start */
	ktime_t last_end;	/* CLOCK_REALTIME of the last cycle's end */
	/*
	 * The last fault (one per start: a fault stops the task), kept
	 * across a restart; the task's state says whether it is stopped on
	 * it.  fault_code 0: none since the load.
	 */
	ktime_t fault_time;	/* CLOCK_REALTIME of it */
	int fault_code;
	const char *fault_pou;	/* points into a program module: use the copy */
	int fault_line;
	char fault_pou_name[IEC_POU_NAME_LEN];	/* copy of *fault_pou */
};

struct iec_resource;

/* The histogram bucket of a release latency of @ns (IEC_HIST_BUCKETS). */
static inline u32 iec_hist_bucket(s64 ns)
{
	u64 us = ns > 0 ? (u64)ns / NSEC_PER_USEC : 0;
	u32 o, b;

	if (us < 32)
		return us;
	o = ilog2(us) - 5;		/* us in [32 << o, 64 << o) */
	b = 32 + 4 * o + ((us >> (o + 3)) & 3);
	return min_t(u32, b, IEC_HIST_BUCKETS - 1);
}

/* A forced variable: its value is written at every cycle boundary. */
struct iec_force {
	struct iec_force *next;
	const struct iec_var_desc *desc;
	struct iec_resource *res;	/* NULL: the configuration's table */
	u32 size;
	u8 value[];
};

/* One TASK: static description from the generator, runtime state. */
struct iec_task {
	const char *name;
	s64 interval_ns;	/* 0: event task */
	int priority;		/* IEC priority, 0 most urgent */
	int single_event;	/* event number of its SINGLE variable, -1 none */
	u32 loop_budget;	/* iterations per cycle before "endless loop" */
	/*
	 * The watchdog ({watchdog ...} pragma, iec2kmod/checks/tasks.py): a
	 * cycle longer than watchdog_ns faults the task where it is (0: no
	 * limit); watchdog_overruns cycles in a row that end after the next
	 * release fault it too (0: no limit).
	 */
	s64 watchdog_ns;
	u32 watchdog_overruns;
	u32 task_id;		/* index in the configuration: its frame areas */
	/*
	 * generated: copy in, run the programs, copy out.  A copy with bound
	 * I/O (iec_io.c) reads its devices before copy-in's image lock and
	 * writes them after copy-out's; a device error raises IEC_FAULT_IO on
	 * the task's ctx, and run() is skipped.
	 */
	void (*copy_in)(struct iec_task *t);
	void (*run)(struct iec_ctx *ctx);
	void (*copy_out)(struct iec_task *t);
	/* NULL, or: drives the task's bound outputs to their safe state
	 * (the thread calls it when it goes idle: stop and fault) */
	void (*io_safe)(struct iec_task *t);
	/*
	 * The GFT slots whose bodies run() calls, ascending: the grace
	 * period of one slot waits only for the tasks that run it, so a
	 * task stuck in one program type does not hold up the others.
	 */
	const u32 *slots;
	u32 nslots;

	/* runtime */
	struct iec_resource *res;
	struct task_struct *thread;
	struct iec_ctx ctx;
	int state;			/* enum iec_task_state */
	bool event_pending;
	/* 0, or the release of the pending event: when its interrupt came
	 * (iec_io.c); written before event_pending */
	ktime_t event_time;
	bool start_request;
	ktime_t first;		/* first release after a start (the epoch) */
	ktime_t until;		/* 0, or: stop before this release ("run") */
	ktime_t next;
	struct iec_task_stats stats;
	struct hrtimer watchdog;	/* armed during a cycle */
	u32 late;			/* overrunning cycles in a row */

	/*
	 * Manager access to the task's program instances (iec_vars.c).  The
	 * task holds var_lock briefly at both ends of a cycle
	 * (iec2kmod_cycle_begin/end): forced values are written there, and
	 * in_cycle tells the manager whether it may read or write the
	 * instance state now (a cycle boundary) or must wait.
	 */
	raw_spinlock_t var_lock;
	bool in_cycle;			/* under var_lock */
	struct iec_force *forces;	/* forced instance variables, under var_lock */

	/*
	 * Acknowledgements the manager waits for, with a bound
	 * (iec2kmod_wait_bound()), instead of a grace period that a task
	 * which never comes back would make endless:
	 *  - cycle_seq counts both ends of every cycle (odd: inside one;
	 *    written under var_lock, the end with release semantics):
	 *    the GFT grace period waits for the cycles that were running
	 *    when a body was replaced (iec_config_rt.c);
	 *  - active is set by the thread while it may run cycles (from a
	 *    start to its acknowledgement of a stop or a fault); it holds a
	 *    reference on its resource module meanwhile, so the module
	 *    cannot go while a cycle may still run, and a stop waits for
	 *    it to clear.
	 */
	unsigned long cycle_seq;
	ktime_t cycle_start;		/* monotonic, of the current cycle */
	unsigned long gp_snap;		/* cycle_seq at a grace period's start */
	bool active;
};

struct iec_resource {
	const char *name;
	int cpu;			/* -1: not pinned */
	struct iec_task *tasks;
	u32 ntasks;
	const struct iec_var_desc *vars;
	u32 nvars;
	struct module *owner;
	/* control, implemented by the resource runtime (static there) */
	int (*start)(struct iec_resource *res);
	/* starts tasks[i] alone if it is not running (a restart) */
	int (*start_task)(struct iec_resource *res, u32 i);
	void (*stop)(struct iec_resource *res);
	/*
	 * First release of the periodic tasks at the next start, set by the
	 * configuration module: every task started by one command shares it,
	 * so tasks released at the same instant run in priority order as in
	 * `iec2kmod sim`.
	 */
	ktime_t epoch;
	ktime_t until;		/* 0, or: periodic tasks stop before this release */
	/* runtime, owned by the configuration module */
	struct list_head node;
	struct kobject *kobj;
	/*
	 * Commands that wait for a cycle boundary of its tasks holding no
	 * mutex (iec_vars.c): taken under iec_resources_lock while the
	 * resource is registered; unregistering waits for it to drop to 0
	 * (at most one command's boundary wait, IEC_BOUNDARY_WAIT_MS).
	 */
	atomic_t users;
};

/* The configuration, described by the generated configuration module. */
struct iec_config {
	const char *name;
	const char *source_hash;	/* sha256 of the IEC sources */
	const char *iface_hash;		/* hash of the configuration's interface */
	struct iec_gft_slot *slots;
	u32 nslots;
	const struct iec_var_desc *vars;	/* globals and process image */
	u32 nvars;
	u32 nevents;			/* SINGLE variables */
};

/* --- exported by the configuration module ----------------------------- */

/* The lock of copy-in/copy-out: a raw spinlock, short bounded sections. */
void iec2kmod_image_lock(void) __acquires(iec_image_lock);
void iec2kmod_image_unlock(void) __releases(iec_image_lock);

/* Runs the body in GFT slot @slot on @self (SRCU read side inside);
 * -ENOENT when the slot is empty, -ENODATA after a fault. */
int iec2kmod_run_program(u32 slot, void *self, struct iec_ctx *ctx);

/* Program-type module init: fills its slot if the interface hash matches. */
int iec2kmod_gft_publish(struct iec_program_type *type);
/* Stages a build for a later publication (insmod ... stage=1). */
int iec2kmod_gft_stage(struct iec_program_type *type);

/* Resource module init/exit. */
int iec2kmod_register_resource(struct iec_resource *res);
void iec2kmod_unregister_resource(struct iec_resource *res);

/* A SINGLE variable rose: wake the event tasks waiting for it. */
void iec2kmod_event(u32 event);

/*
 * Bounded waits.  Nothing the manager does waits for a task for ever: a
 * stop, a slot clear or a publication waits at most
 * iec2kmod_wait_bound(interval) for a task with that period (wait_ms, a
 * parameter of the configuration module, default 1000 ms, plus four
 * periods), then fails with -ETIMEDOUT and a message naming the task.
 * iec2kmod_task_idle() is the thread's acknowledgement of a stop.
 */
unsigned long iec2kmod_wait_bound(s64 interval_ns);
void iec2kmod_task_idle(struct iec_task *t);

/*
 * Manager access (iec_vars.c), called by the resource runtime:
 *  - iec2kmod_cycle_begin/end at both ends of every task cycle (they take
 *    the task's var_lock and write its forced instance variables);
 *  - iec2kmod_force_globals from a task's copy-out, under the image lock,
 *    after the written globals were stored (forced globals win);
 *  - iec2kmod_resource_gone from resource exit, after unregistering:
 *    drops the forces that point into the resource module.
 */
void iec2kmod_cycle_begin(struct iec_task *t);
void iec2kmod_cycle_end(struct iec_task *t);
void iec2kmod_force_globals(void);
void iec2kmod_resource_gone(struct iec_resource *res);

/* --- inside the configuration module (iec_config_rt.c, iec_ctl*.c) ---- */
int iec_config_init(struct iec_config *cfg);
void iec_config_exit(struct iec_config *cfg);
extern struct iec_config *iec_cfg;
extern struct list_head iec_resources;
extern struct mutex iec_resources_lock;
int iec_ctl_init(void);
void iec_ctl_exit(void);
int iec_gft_clear(long slot);	/* -1: every slot */
int iec_gft_publish_staged(long slot);	/* -1: every staged slot */
int iec_gft_unstage(long slot);		/* -1: every slot */
extern struct wait_queue_head iec_ack_wq;
int iec_wait_resource_idle(struct iec_resource *res, unsigned long deadline);
void iec_task_stuck_report(const char *what, struct iec_resource *r,
			   struct iec_task *t);

#endif /* IEC_KMOD_H */
