/* SPDX-License-Identifier: GPL-2.0-only OR MIT */
/*
 * iec_nl.h - the generic netlink protocol of the configuration module
 * (family IEC_NL_FAMILY, implemented in iec_ctl_nl.c and iec_vars.c).
 * plc-manager mirrors these numbers in manager/netlink.py; tests compare
 * both.
 *
 * One attribute space for the whole family: every nest (a resource, a
 * task, a slot, a variable) uses the same numbers.  Every command needs
 * CAP_NET_ADMIN (GENL_ADMIN_PERM; STATUS, VAR_GET and VAR_LIST check it in
 * their handlers, which also admit the read-only group monitor_gid if the
 * configuration module was loaded with one) and is validated strictly against its
 * own policy: an attribute a command does not take is refused.
 *
 *   IEC_CMD_STATUS [SLOTS_ONLY] -> CONFIG attributes, RESOURCE nests (with TASK
 *                          nests), SLOT nests
 *   IEC_CMD_VAR_GET     VAR{PATH | TABLE+INDEX}...  -> VAR{...VALUE}...
 *   IEC_CMD_VAR_LIST    (dump) one message per variable, no VALUE
 *   IEC_CMD_VAR_SET     VAR{PATH | TABLE+INDEX, VALUE}...
 *   IEC_CMD_VAR_FORCE   VAR{PATH | TABLE+INDEX, VALUE}...
 *   IEC_CMD_VAR_UNFORCE VAR{PATH | TABLE+INDEX}... or ALL
 *   IEC_CMD_RES_START   [NAME]  (no NAME: every resource; "res.task": one task)
 *   IEC_CMD_RES_STOP    [NAME]
 *   IEC_CMD_SLOT_CLEAR  [SLOT_INDEX]  (none: every slot)
 *   IEC_CMD_SLOT_PUBLISH [SLOT_INDEX] publishes what insmod stage=1 staged
 *                          (none: every staged slot); ENOENT: none staged
 *   IEC_CMD_SLOT_UNSTAGE [SLOT_INDEX] drops staged builds unpublished
 *
 * VALUE is the C object's bytes in host order (kind and size say how to
 * read them); for STRING/WSTRING it is the length (u16) and the
 * characters with their terminating NUL.  Requests naming several
 * variables are checked completely before anything is written; a request
 * naming a variable twice is refused (EINVAL).  The kernel checks every
 * value itself (size, BOOL 0/1, a string against its declared length,
 * subrange bounds: ERANGE, enumeration values: ERANGE); read-only
 * variables (CONSTANT, FB outputs, SFC steps) refuse VAR_SET and
 * VAR_FORCE (EACCES).  String attributes (PATH, TABLE, NAME) end exactly
 * at their NUL.  Each variable is written whole; the globals of one
 * VAR_SET reach the tasks in image-lock holds of at most 512 bytes
 * (IEC_IMAGE_HOLD_BYTES in iec_vars.c), so a task may see some of them
 * before the others.
 */
#ifndef IEC_NL_H
#define IEC_NL_H

#define IEC_NL_FAMILY		"iec2kmod"
#define IEC_NL_VERSION		1
#define IEC_NL_VALUE_MAX	65000	/* bytes of one VALUE */
#define IEC_NL_MAX_VARS		256	/* variables in one request */
#define IEC_NL_MAX_FORCES	128	/* forced variables at a time */

enum iec_nl_cmd {
	IEC_CMD_UNSPEC,
	IEC_CMD_STATUS,
	IEC_CMD_VAR_GET,
	IEC_CMD_VAR_LIST,
	IEC_CMD_VAR_SET,
	IEC_CMD_VAR_FORCE,
	IEC_CMD_VAR_UNFORCE,
	IEC_CMD_RES_START,
	IEC_CMD_RES_STOP,
	IEC_CMD_SLOT_CLEAR,
	IEC_CMD_SLOT_PUBLISH,
	IEC_CMD_SLOT_UNSTAGE,
	__IEC_CMD_MAX
};

enum iec_nl_attr {
	IEC_A_UNSPEC,
	IEC_A_PAD,		/* padding of 64-bit attributes */
	IEC_A_ABI,		/* u32: IEC_KMOD_ABI */
	IEC_A_NAME,		/* string: configuration, resource, task, type */
	IEC_A_MODULE,		/* string: module name */
	IEC_A_SOURCE_HASH,	/* string */
	IEC_A_IFACE_HASH,	/* string: configuration interface hash */
	IEC_A_NOW_NS,		/* s64: CLOCK_REALTIME of the reply */
	IEC_A_RESOURCE,		/* nest: one resource */
	IEC_A_TASK,		/* nest: one task (inside a RESOURCE) */
	IEC_A_SLOT,		/* nest: one GFT slot */
	IEC_A_SLOT_INDEX,	/* u32 */
	IEC_A_CPU,		/* s32: CPU the resource is pinned to, -1 none */
	IEC_A_LAST_CPU,		/* u32: CPU the task's thread last ran on */
	IEC_A_STATE,		/* u8: 0 stopped, 1 running, 2 fault */
	IEC_A_INTERVAL_NS,	/* s64: 0 for an event task */
	IEC_A_PRIORITY,		/* s32: IEC priority */
	IEC_A_CYCLES,		/* u64 */
	IEC_A_OVERRUNS,		/* u64 */
	IEC_A_FAULTS,		/* u64 */
	IEC_A_EXEC_MIN_NS,	/* s64 */
	IEC_A_EXEC_AVG_NS,	/* s64 */
	IEC_A_EXEC_MAX_NS,	/* s64 */
	IEC_A_LAT_AVG_NS,	/* s64: release jitter */
	IEC_A_LAT_MAX_NS,	/* s64 */
	IEC_A_HIST,		/* binary: u64[IEC_HIST_BUCKETS] latency (log-linear) */
	IEC_A_FAULT_NAME,	/* string: the last fault (kept across a restart) */
	IEC_A_FAULT_POU,	/* string */
	IEC_A_FAULT_LINE,	/* s32 */
	IEC_A_BUILD_ID,		/* string */
	IEC_A_SLOT_IFACE,	/* u64: interface hash of a slot */
	IEC_A_SINCE_NS,		/* s64: CLOCK_REALTIME of the last publication */
	IEC_A_PUBLICATIONS,	/* u64 */
	IEC_A_NFORCED,		/* u32: forced variables */
	IEC_A_VAR,		/* nest: one variable */
	IEC_A_PATH,		/* string: IEC path */
	IEC_A_TABLE,		/* string: "" configuration, else resource */
	IEC_A_INDEX,		/* u32: index in its table */
	IEC_A_KIND,		/* u8: b i u f t e s w */
	IEC_A_SIZE,		/* u32: bytes of the C object */
	IEC_A_WRITABLE,		/* u8 */
	IEC_A_FORCED,		/* u8 */
	IEC_A_EVENT,		/* u32: 1 + SINGLE event number, 0 none */
	IEC_A_TASK_INDEX,	/* u32: 1 + task index in its resource, 0 global */
	IEC_A_VALUE,		/* binary */
	IEC_A_ALL,		/* flag */
	IEC_A_IN_CYCLE_NS,	/* s64: time inside the current cycle, if in one */
	IEC_A_SEL_EVALUATED,	/* u64: blocks evaluated (--selective modules) */
	IEC_A_SEL_SKIPPED,	/* u64: blocks skipped (--selective modules) */
	IEC_A_STARTS,		/* u64: starts of a task since the load */
	IEC_A_STARTED_NS,	/* s64: CLOCK_REALTIME of its last start */
	IEC_A_FAULT_NS,		/* s64: CLOCK_REALTIME of its last fault */
	IEC_A_STAGED,		/* string: build id staged in a slot */
	IEC_A_FIRST_RUN_NS,	/* s64: CLOCK_REALTIME of the body's first cycle */
	IEC_A_SLOTS_ONLY,	/* flag: a STATUS without the resources */
	IEC_A_FIRST_RUN_TASK,	/* string: "res.task" whose cycle ran the body first */
	IEC_A_LAST_END_NS,	/* s64: CLOCK_REALTIME of the end of a task's last cycle */
	__IEC_A_MAX
};
#define IEC_A_MAX (__IEC_A_MAX - 1)

#endif /* IEC_NL_H */
