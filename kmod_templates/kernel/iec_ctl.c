// SPDX-License-Identifier: GPL-2.0-only OR MIT
/*
 * iec_ctl.c - the configuration's control plane.
 *
 * sysfs, for people and shell scripts (root-only, 0400 / 0200):
 *   /sys/kernel/iec2kmod/<configuration>/status    resources, tasks, slots
 *   /sys/kernel/iec2kmod/<configuration>/control   "start <resource>|all",
 *                                                   "start <resource>.<task>"
 *                                                   (that task alone: a
 *                                                   restart after a fault),
 *                                                   "stop <resource>|all",
 *                                                   "run <resource>|all MS"
 *                                                   (start; every periodic
 *                                                   task stops by itself
 *                                                   before its first release
 *                                                   MS ms after the start,
 *                                                   running late releases
 *                                                   late instead of skipping
 *                                                   them: a fixed number of
 *                                                   cycles)
 *                                                   "clear <slot>|all"
 *
 * Generic netlink family "iec2kmod" (iec_nl.h), for plc-manager: status,
 * variable list/read/write/force/unforce, resource (or task) start, resource
 * stop, slot clear.
 * Every command needs CAP_NET_ADMIN in the initial namespace and is checked
 * strictly against its own policy.  Commands run one at a time
 * (iec_ctl_mutex); they may sleep, but never while holding a raw lock.
 *
 * Variable access and the real-time tasks:
 *  - globals (configuration, resource and process image) are read and
 *    written under the image lock, the raw spinlock of copy-in/copy-out,
 *    so a task sees a manager write whole, at its next copy-in; a write
 *    that raises a SINGLE variable wakes its event tasks;
 *  - program-instance variables belong to the task that runs the
 *    instance; the manager touches them only between two cycles of that
 *    task: under the task's var_lock with in_cycle false (the task sets it
 *    under the same lock at both ends of a cycle).  While a cycle runs,
 *    the command sleeps and tries again; the task never waits longer than
 *    one memcpy of one variable;
 *  - forced variables keep their forced value at cycle boundaries: forced
 *    globals are written back after every copy-out (under the image lock,
 *    so no task ever copies in an unforced value); forced instance
 *    variables are written at both ends of every cycle of their task.
 *    Forcing an instance variable that a program connection assigns
 *    (an input) has no lasting effect: force the global or the %I
 *    address it is connected to.  A task that writes a forced SINGLE
 *    variable may still wake its event tasks: the edge is detected in the
 *    copy-out before the forced value is written back.
 */
#include <linux/delay.h>
#include <linux/kobject.h>
#include <linux/module.h>
#include <linux/mutex.h>
#include <linux/overflow.h>
#include <linux/sched.h>
#include <linux/sched/signal.h>
#include <linux/slab.h>
#include <linux/string.h>
#include <linux/sysfs.h>
#include <linux/timekeeping.h>
#include <asm/unaligned.h>
#include <net/genetlink.h>

#include "iec_kmod.h"
#include "iec_nl.h"

static struct kobject *iec_root_kobj;
static struct kobject *iec_cfg_kobj;

static const char *const iec_state_names[] = { "stopped", "running", "fault" };

/* serialises netlink commands, sysfs control and the force lists */
static DEFINE_MUTEX(iec_ctl_mutex);
/* forced globals: changed under iec_ctl_mutex and the image lock, walked
 * under the image lock */
static struct iec_force *iec_global_forces;

/* ------------------------------------------------------------------ */
/* forces, called from the real-time tasks                            */
/* ------------------------------------------------------------------ */

static void iec_forces_write(const struct iec_force *f)
{
	for (; f; f = f->next)
		memcpy(f->desc->addr, f->value, f->size);
}

void iec2kmod_cycle_begin(struct iec_task *t)
{
	ktime_t now = ktime_get();

	raw_spin_lock(&t->var_lock);
	iec_forces_write(t->forces);
	t->in_cycle = true;
	WRITE_ONCE(t->cycle_start, now);
	WRITE_ONCE(t->cycle_seq, t->cycle_seq + 1);	/* odd: in a cycle */
	raw_spin_unlock(&t->var_lock);
}
EXPORT_SYMBOL_GPL(iec2kmod_cycle_begin);

void iec2kmod_cycle_end(struct iec_task *t)
{
	raw_spin_lock(&t->var_lock);
	iec_forces_write(t->forces);
	t->in_cycle = false;
	/* the cycle's body calls before the grace period sees it end */
	smp_store_release(&t->cycle_seq, t->cycle_seq + 1);
	raw_spin_unlock(&t->var_lock);
	if (wq_has_sleeper(&iec_ack_wq))
		wake_up_all(&iec_ack_wq);
}
EXPORT_SYMBOL_GPL(iec2kmod_cycle_end);

/* The caller holds the image lock (a task's copy-out). */
void iec2kmod_force_globals(void)
{
	iec_forces_write(iec_global_forces);
}
EXPORT_SYMBOL_GPL(iec2kmod_force_globals);

static void iec_forces_free(struct iec_force *f)
{
	while (f) {
		struct iec_force *next = f->next;

		kfree(f);
		f = next;
	}
}

/* Unlinks the force of @desc from the list at @pp; returns it or NULL. */
static struct iec_force *iec_force_unlink(struct iec_force **pp,
					  const struct iec_var_desc *desc)
{
	struct iec_force *f;

	for (; (f = *pp); pp = &f->next) {
		if (f->desc == desc) {
			*pp = f->next;
			f->next = NULL;
			return f;
		}
	}
	return NULL;
}

/*
 * Resource exit, after it unregistered and its threads stopped: drops the
 * forces that point into the resource module (its globals, its instances).
 */
void iec2kmod_resource_gone(struct iec_resource *res)
{
	struct iec_force *drop = NULL, *f, **pp;
	u32 i;

	mutex_lock(&iec_ctl_mutex);
	iec2kmod_image_lock();
	for (pp = &iec_global_forces; (f = *pp);) {
		if (f->res == res) {
			*pp = f->next;
			f->next = drop;
			drop = f;
		} else {
			pp = &f->next;
		}
	}
	iec2kmod_image_unlock();
	for (i = 0; i < res->ntasks; i++) {
		struct iec_task *t = &res->tasks[i];

		raw_spin_lock(&t->var_lock);
		f = t->forces;
		t->forces = NULL;
		raw_spin_unlock(&t->var_lock);
		iec_forces_free(f);
	}
	mutex_unlock(&iec_ctl_mutex);
	iec_forces_free(drop);
}
EXPORT_SYMBOL_GPL(iec2kmod_resource_gone);

/* ------------------------------------------------------------------ */
/* variables                                                          */
/* ------------------------------------------------------------------ */

struct iec_var_ref {
	const struct iec_var_desc *desc;
	struct iec_resource *res;	/* NULL: the configuration's table */
	struct iec_task *task;		/* NULL: a global */
	u32 index;
	const struct nlattr *value;	/* VALUE of a write or force */
};

static void iec_var_ref_set(struct iec_var_ref *ref, struct iec_resource *res,
			    const struct iec_var_desc *vars, u32 i)
{
	ref->desc = &vars[i];
	ref->res = res;
	ref->index = i;
	ref->task = NULL;
	if (res && vars[i].task && vars[i].task <= res->ntasks)
		ref->task = &res->tasks[vars[i].task - 1];
}

static struct iec_resource *iec_resource_find(const char *name)
{
	struct iec_resource *r;

	lockdep_assert_held(&iec_resources_lock);
	list_for_each_entry(r, &iec_resources, node)
		if (!strcasecmp(r->name, name))
			return r;
	return NULL;
}

/* IEC names are case-insensitive: so are variable paths. */
static int iec_var_find(const char *path, struct iec_var_ref *ref)
{
	struct iec_resource *r;
	u32 i;

	lockdep_assert_held(&iec_resources_lock);
	for (i = 0; i < iec_cfg->nvars; i++) {
		if (!strcasecmp(iec_cfg->vars[i].path, path)) {
			iec_var_ref_set(ref, NULL, iec_cfg->vars, i);
			return 0;
		}
	}
	list_for_each_entry(r, &iec_resources, node) {
		for (i = 0; i < r->nvars; i++) {
			if (!strcasecmp(r->vars[i].path, path)) {
				iec_var_ref_set(ref, r, r->vars, i);
				return 0;
			}
		}
	}
	return -ENOENT;
}

static const struct nla_policy iec_nl_sel_policy[IEC_A_MAX + 1] = {
	[IEC_A_PATH] = { .type = NLA_NUL_STRING, .len = 511 },
	[IEC_A_TABLE] = { .type = NLA_NUL_STRING, .len = 63 },
	[IEC_A_INDEX] = { .type = NLA_U32 },
};

static const struct nla_policy iec_nl_val_policy[IEC_A_MAX + 1] = {
	[IEC_A_PATH] = { .type = NLA_NUL_STRING, .len = 511 },
	[IEC_A_TABLE] = { .type = NLA_NUL_STRING, .len = 63 },
	[IEC_A_INDEX] = { .type = NLA_U32 },
	[IEC_A_VALUE] = { .type = NLA_BINARY, .len = IEC_NL_VALUE_MAX },
};

/* A VAR nest: PATH, or TABLE and INDEX (and PATH, which must agree). */
static int iec_var_select(const struct nlattr *nest,
			  const struct nla_policy *policy,
			  struct iec_var_ref *ref, struct netlink_ext_ack *extack)
{
	struct nlattr *tb[IEC_A_MAX + 1];
	int err;

	err = nla_parse_nested(tb, IEC_A_MAX, nest, policy, extack);
	if (err)
		return err;
	if (tb[IEC_A_TABLE] && tb[IEC_A_INDEX]) {
		const char *table = nla_data(tb[IEC_A_TABLE]);
		u32 i = nla_get_u32(tb[IEC_A_INDEX]);
		struct iec_resource *r = NULL;

		if (*table) {
			r = iec_resource_find(table);
			if (!r) {
				NL_SET_ERR_MSG_ATTR(extack, tb[IEC_A_TABLE],
						    "no such resource");
				return -ENOENT;
			}
		}
		if (i >= (r ? r->nvars : iec_cfg->nvars)) {
			NL_SET_ERR_MSG_ATTR(extack, tb[IEC_A_INDEX],
					    "variable index out of range");
			return -ENOENT;
		}
		iec_var_ref_set(ref, r, r ? r->vars : iec_cfg->vars, i);
		if (tb[IEC_A_PATH] &&
		    strcasecmp(ref->desc->path, nla_data(tb[IEC_A_PATH]))) {
			NL_SET_ERR_MSG_ATTR(extack, tb[IEC_A_PATH],
					    "variable index and path disagree");
			return -ESTALE;
		}
	} else if (tb[IEC_A_PATH]) {
		err = iec_var_find(nla_data(tb[IEC_A_PATH]), ref);
		if (err) {
			NL_SET_ERR_MSG_ATTR(extack, tb[IEC_A_PATH],
					    "no such variable");
			return err;
		}
	} else {
		NL_SET_ERR_MSG_ATTR(extack, nest,
				    "a variable needs PATH, or TABLE and INDEX");
		return -EINVAL;
	}
	ref->value = tb[IEC_A_VALUE];
	return 0;
}

/* Size check of a VALUE for a variable (types and ranges: plc-manager). */
static int iec_value_check(const struct iec_var_ref *ref,
			   struct netlink_ext_ack *extack)
{
	const struct iec_var_desc *d = ref->desc;
	const u8 *p;
	u32 len;

	if (!ref->value) {
		NL_SET_ERR_MSG(extack, "a value is missing");
		return -EINVAL;
	}
	p = nla_data(ref->value);
	len = nla_len(ref->value);
	if (d->kind == 's' || d->kind == 'w') {
		u32 cs = d->kind == 'w' ? 2 : 1;
		u32 n;

		if (len < 2 + cs)
			goto bad_size;
		n = get_unaligned((const u16 *)p);
		if (len != 2 + (n + 1) * cs || len > d->size)
			goto bad_size;
		if (p[len - 1] || p[len - cs])
			goto bad_size;	/* the terminating NUL */
		return 0;
	}
	if (len != d->size)
		goto bad_size;
	if (d->kind == 'b' && p[0] > 1) {
		NL_SET_ERR_MSG_ATTR(extack, ref->value, "a BOOL is 0 or 1");
		return -EINVAL;
	}
	return 0;

bad_size:
	NL_SET_ERR_MSG_ATTR(extack, ref->value,
			    "value size does not fit the variable");
	return -EMSGSIZE;
}

/*
 * Copies @len bytes from @src to @dst under @t's var_lock at a cycle
 * boundary (no cycle running).  Sleeps between tries; -EBUSY if the task
 * stays inside one cycle for about a second.
 */
#define IEC_BOUNDARY_TRIES	1000

static int iec_task_boundary_copy(struct iec_task *t, void *dst,
				  const void *src, u32 len)
{
	int i;

	for (i = 0;; i++) {
		raw_spin_lock(&t->var_lock);
		if (!t->in_cycle) {
			memcpy(dst, src, len);
			/* selective blocks of the task see a write they do not compare */
			t->ctx.sel_epoch++;
			raw_spin_unlock(&t->var_lock);
			return 0;
		}
		raw_spin_unlock(&t->var_lock);
		if (i == IEC_BOUNDARY_TRIES)
			return -EBUSY;
		if (fatal_signal_pending(current))
			return -EINTR;
		if (i < 100)
			usleep_range(20, 50);
		else
			usleep_range(1000, 1200);
	}
}

static u32 iec_value_len(const struct iec_var_desc *d)
{
	return min_t(u32, d->size, IEC_NL_VALUE_MAX);
}

static int iec_var_read(const struct iec_var_ref *ref, void *buf, u32 len)
{
	if (ref->task)
		return iec_task_boundary_copy(ref->task, buf, ref->desc->addr,
					      len);
	iec2kmod_image_lock();
	memcpy(buf, ref->desc->addr, len);
	iec2kmod_image_unlock();
	return 0;
}

static bool iec_rises(const struct iec_var_desc *d, const void *value)
{
	return d->single_event && d->kind == 'b' && !*(const u8 *)d->addr &&
	       *(const u8 *)value;
}

static bool iec_var_forced(const struct iec_var_ref *ref)
{
	const struct iec_force *f;

	lockdep_assert_held(&iec_ctl_mutex);
	f = ref->task ? ref->task->forces : iec_global_forces;
	for (; f; f = f->next)
		if (f->desc == ref->desc)
			return true;
	return false;
}

static u32 iec_forced_count(void)
{
	const struct iec_force *f;
	struct iec_resource *r;
	u32 n = 0, i;

	for (f = iec_global_forces; f; f = f->next)
		n++;
	list_for_each_entry(r, &iec_resources, node)
		for (i = 0; i < r->ntasks; i++)
			for (f = r->tasks[i].forces; f; f = f->next)
				n++;
	return n;
}

/* ------------------------------------------------------------------ */
/* generic netlink                                                    */
/* ------------------------------------------------------------------ */

static struct genl_family iec_nl_family;

/* Attributes of one variable, without its value. */
static int iec_put_var(struct sk_buff *skb, const struct iec_var_ref *ref)
{
	const struct iec_var_desc *d = ref->desc;

	if (nla_put_string(skb, IEC_A_PATH, d->path) ||
	    nla_put_string(skb, IEC_A_TABLE, ref->res ? ref->res->name : "") ||
	    nla_put_u32(skb, IEC_A_INDEX, ref->index) ||
	    nla_put_u8(skb, IEC_A_KIND, d->kind) ||
	    nla_put_u32(skb, IEC_A_SIZE, d->size) ||
	    nla_put_u8(skb, IEC_A_WRITABLE, d->writable) ||
	    nla_put_u8(skb, IEC_A_FORCED, iec_var_forced(ref)) ||
	    nla_put_u32(skb, IEC_A_EVENT, d->single_event) ||
	    nla_put_u32(skb, IEC_A_TASK_INDEX, ref->task ? d->task : 0))
		return -EMSGSIZE;
	return 0;
}

static size_t iec_var_msg_size(const struct iec_var_ref *ref, bool value)
{
	const struct iec_var_desc *d = ref->desc;

	return nla_total_size(0) +
	       nla_total_size(strlen(d->path) + 1) +
	       nla_total_size(ref->res ? strlen(ref->res->name) + 1 : 1) +
	       7 * nla_total_size(sizeof(u32)) +
	       (value ? nla_total_size(iec_value_len(d)) : 0);
}

static int iec_put_task(struct sk_buff *skb, struct iec_task *t)
{
	const struct iec_task_stats *s = &t->stats;
	u64 cycles = READ_ONCE(s->cycles);
	struct nlattr *nest;
	u64 evaluated;

	nest = nla_nest_start(skb, IEC_A_TASK);
	if (!nest)
		return -EMSGSIZE;
	if (nla_put_string(skb, IEC_A_NAME, t->name) ||
	    nla_put_u8(skb, IEC_A_STATE, READ_ONCE(t->state)) ||
	    nla_put_s64(skb, IEC_A_INTERVAL_NS, t->interval_ns, IEC_A_PAD) ||
	    nla_put_s32(skb, IEC_A_PRIORITY, t->priority) ||
	    nla_put_u32(skb, IEC_A_LAST_CPU, t->thread ? task_cpu(t->thread) : 0) ||
	    nla_put_u64_64bit(skb, IEC_A_CYCLES, cycles, IEC_A_PAD) ||
	    nla_put_u64_64bit(skb, IEC_A_OVERRUNS, s->overruns, IEC_A_PAD) ||
	    nla_put_u64_64bit(skb, IEC_A_FAULTS, s->faults, IEC_A_PAD) ||
	    nla_put_s64(skb, IEC_A_EXEC_MIN_NS, s->exec_min_ns, IEC_A_PAD) ||
	    nla_put_s64(skb, IEC_A_EXEC_AVG_NS,
			cycles ? div64_s64(s->exec_sum_ns, cycles) : 0, IEC_A_PAD) ||
	    nla_put_s64(skb, IEC_A_EXEC_MAX_NS, s->exec_max_ns, IEC_A_PAD) ||
	    nla_put_s64(skb, IEC_A_LAT_AVG_NS,
			cycles ? div64_s64(s->latency_sum_ns, cycles) : 0, IEC_A_PAD) ||
	    nla_put_s64(skb, IEC_A_LAT_MAX_NS, s->latency_max_ns, IEC_A_PAD) ||
	    nla_put(skb, IEC_A_HIST, sizeof(s->hist), s->hist))
		goto cancel;
	/* inside a cycle now: for how long (a task that does not come back) */
	if ((smp_load_acquire(&t->cycle_seq) & 1) &&
	    nla_put_s64(skb, IEC_A_IN_CYCLE_NS,
			ktime_to_ns(ktime_sub(ktime_get(), READ_ONCE(t->cycle_start))),
			IEC_A_PAD))
		goto cancel;
	/* selective execution: the task's counts of blocks (iec_sel.h) */
	evaluated = READ_ONCE(t->ctx.sel_evaluated) + READ_ONCE(t->ctx.sel_plain);
	if ((evaluated || READ_ONCE(t->ctx.sel_skipped)) &&
	    (nla_put_u64_64bit(skb, IEC_A_SEL_EVALUATED, evaluated, IEC_A_PAD) ||
	     nla_put_u64_64bit(skb, IEC_A_SEL_SKIPPED,
			       READ_ONCE(t->ctx.sel_skipped), IEC_A_PAD)))
		goto cancel;
	if (s->fault_code &&
	    (nla_put_string(skb, IEC_A_FAULT_NAME, iec_fault_name(s->fault_code)) ||
	     nla_put_string(skb, IEC_A_FAULT_POU, s->fault_pou_name) ||
	     nla_put_s32(skb, IEC_A_FAULT_LINE, s->fault_line) ||
	     nla_put_s64(skb, IEC_A_FAULT_NS, ktime_to_ns(s->fault_time), IEC_A_PAD)))
		goto cancel;
	if (nla_put_u64_64bit(skb, IEC_A_STARTS, s->starts, IEC_A_PAD) ||
	    nla_put_s64(skb, IEC_A_STARTED_NS, ktime_to_ns(s->started), IEC_A_PAD))
		goto cancel;
	nla_nest_end(skb, nest);
	return 0;

cancel:
	nla_nest_cancel(skb, nest);
	return -EMSGSIZE;
}

static int iec_put_resource(struct sk_buff *skb, struct iec_resource *r)
{
	struct nlattr *nest;
	u32 i;

	nest = nla_nest_start(skb, IEC_A_RESOURCE);
	if (!nest)
		return -EMSGSIZE;
	if (nla_put_string(skb, IEC_A_NAME, r->name) ||
	    nla_put_string(skb, IEC_A_MODULE, module_name(r->owner)) ||
	    nla_put_s32(skb, IEC_A_CPU, r->cpu))
		goto cancel;
	for (i = 0; i < r->ntasks; i++)
		if (iec_put_task(skb, &r->tasks[i]))
			goto cancel;
	nla_nest_end(skb, nest);
	return 0;

cancel:
	nla_nest_cancel(skb, nest);
	return -EMSGSIZE;
}

/*
 * A slot's program type lives in its module.  The reference is read under
 * rcu_read_lock(): a replaced module is freed only after the
 * synchronize_rcu() of module removal, so what we read stays valid.
 */
/* "res.task" of the task with @task_id; the caller holds iec_resources_lock */
static int iec_put_task_path(struct sk_buff *skb, int attr, u32 task_id)
{
	struct iec_resource *r;
	char path[128];
	u32 k;

	list_for_each_entry(r, &iec_resources, node)
		for (k = 0; k < r->ntasks; k++)
			if (r->tasks[k].task_id == task_id) {
				snprintf(path, sizeof(path), "%s.%s", r->name,
					 r->tasks[k].name);
				return nla_put_string(skb, attr, path);
			}
	return 0;	/* its resource is gone */
}

/* One GFT slot; the caller holds iec_resources_lock. */
static int iec_put_slot(struct sk_buff *skb, u32 i)
{
	const struct iec_gft_slot *slot = &iec_cfg->slots[i];
	const struct iec_program_type *p, *staged;
	struct nlattr *nest;
	int err = 0;

	nest = nla_nest_start(skb, IEC_A_SLOT);
	if (!nest)
		return -EMSGSIZE;
	rcu_read_lock();
	p = rcu_dereference_raw(slot->cur);
	if (nla_put_u32(skb, IEC_A_SLOT_INDEX, i) ||
	    nla_put_string(skb, IEC_A_NAME, slot->type_name) ||
	    nla_put_u64_64bit(skb, IEC_A_SLOT_IFACE, slot->iface_hash, IEC_A_PAD) ||
	    nla_put_s64(skb, IEC_A_SINCE_NS, ktime_to_ns(slot->since), IEC_A_PAD) ||
	    nla_put_u64_64bit(skb, IEC_A_PUBLICATIONS, slot->publications, IEC_A_PAD) ||
	    (p && (nla_put_string(skb, IEC_A_MODULE, module_name(p->owner)) ||
		   nla_put_string(skb, IEC_A_BUILD_ID, p->build_id) ||
		   nla_put_s64(skb, IEC_A_FIRST_RUN_NS, READ_ONCE(p->first_run_ns),
			       IEC_A_PAD) ||
		   (READ_ONCE(p->first_run_task) &&
		    iec_put_task_path(skb, IEC_A_FIRST_RUN_TASK,
				      READ_ONCE(p->first_run_task) - 1)))))
		err = -EMSGSIZE;
	/* a staged build is dropped under iec_ctl_mutex (held): it stays */
	staged = READ_ONCE(slot->staged);
	if (!err && staged && nla_put_string(skb, IEC_A_STAGED, staged->build_id))
		err = -EMSGSIZE;
	rcu_read_unlock();
	if (err) {
		nla_nest_cancel(skb, nest);
		return err;
	}
	nla_nest_end(skb, nest);
	return 0;
}

static size_t iec_status_size(void)
{
	struct iec_resource *r;
	size_t n = 512 + strlen(iec_cfg->name) + strlen(iec_cfg->source_hash) +
		   strlen(iec_cfg->iface_hash);
	u32 i;

	list_for_each_entry(r, &iec_resources, node) {
		n += 256 + strlen(r->name);
		for (i = 0; i < r->ntasks; i++)
			n += 512 + strlen(r->tasks[i].name) + IEC_POU_NAME_LEN +
			     IEC_HIST_BUCKETS * sizeof(u64);
	}
	for (i = 0; i < iec_cfg->nslots; i++)
		n += 460 + strlen(iec_cfg->slots[i].type_name) + MODULE_NAME_LEN;
	return n;
}

/*
 * The status; with SLOTS_ONLY without the resources and their tasks (the
 * swap's confirmation polls the slots: a reply a tenth of the size).
 */
static int iec_nl_status(struct sk_buff *skb, struct genl_info *info)
{
	bool slots_only = nla_get_flag(info->attrs[IEC_A_SLOTS_ONLY]);
	struct iec_resource *r;
	struct sk_buff *msg;
	void *hdr;
	u32 i;
	int err = -EMSGSIZE;

	mutex_lock(&iec_ctl_mutex);
	mutex_lock(&iec_resources_lock);
	msg = genlmsg_new(iec_status_size(), GFP_KERNEL);
	if (!msg) {
		err = -ENOMEM;
		goto out;
	}
	hdr = genlmsg_put_reply(msg, info, &iec_nl_family, 0, IEC_CMD_STATUS);
	if (!hdr)
		goto out_free;
	if (nla_put_u32(msg, IEC_A_ABI, IEC_KMOD_ABI) ||
	    nla_put_string(msg, IEC_A_NAME, iec_cfg->name) ||
	    nla_put_string(msg, IEC_A_MODULE, module_name(THIS_MODULE)) ||
	    nla_put_string(msg, IEC_A_SOURCE_HASH, iec_cfg->source_hash) ||
	    nla_put_string(msg, IEC_A_IFACE_HASH, iec_cfg->iface_hash) ||
	    nla_put_s64(msg, IEC_A_NOW_NS, ktime_get_real_ns(), IEC_A_PAD) ||
	    nla_put_u32(msg, IEC_A_NFORCED, iec_forced_count()))
		goto out_free;
	list_for_each_entry(r, &iec_resources, node)
		if (!slots_only && iec_put_resource(msg, r))
			goto out_free;
	for (i = 0; i < iec_cfg->nslots; i++)
		if (iec_put_slot(msg, i))
			goto out_free;
	genlmsg_end(msg, hdr);
	mutex_unlock(&iec_resources_lock);
	mutex_unlock(&iec_ctl_mutex);
	return genlmsg_reply(msg, info);

out_free:
	nlmsg_free(msg);
out:
	mutex_unlock(&iec_resources_lock);
	mutex_unlock(&iec_ctl_mutex);
	return err;
}

/*
 * Resolves every VAR nest of a request into refs[] (kcalloc'ed, *n set).
 * The caller holds iec_ctl_mutex and iec_resources_lock.
 */
static int iec_nl_vars(struct genl_info *info, const struct nla_policy *policy,
		       struct iec_var_ref **refs, u32 *n)
{
	const struct nlattr *a;
	u32 count = 0, i = 0;
	int rem, err;

	nla_for_each_attr(a, genlmsg_data(info->genlhdr),
			  genlmsg_len(info->genlhdr), rem)
		if (nla_type(a) == IEC_A_VAR)
			count++;
	*refs = NULL;
	*n = 0;
	if (!count)
		return 0;
	if (count > IEC_NL_MAX_VARS) {
		NL_SET_ERR_MSG(info->extack, "too many variables in one request");
		return -E2BIG;
	}
	*refs = kcalloc(count, sizeof(**refs), GFP_KERNEL);
	if (!*refs)
		return -ENOMEM;
	nla_for_each_attr(a, genlmsg_data(info->genlhdr),
			  genlmsg_len(info->genlhdr), rem) {
		if (nla_type(a) != IEC_A_VAR)
			continue;
		err = iec_var_select(a, policy, &(*refs)[i++], info->extack);
		if (err) {
			kfree(*refs);
			*refs = NULL;
			return err;
		}
	}
	*n = count;
	return 0;
}

static int iec_nl_var_get(struct sk_buff *skb, struct genl_info *info)
{
	struct iec_var_ref *refs;
	struct sk_buff *msg = NULL;
	size_t size = 0;
	void *hdr;
	u32 n, i;
	int err;

	mutex_lock(&iec_ctl_mutex);
	mutex_lock(&iec_resources_lock);
	err = iec_nl_vars(info, iec_nl_sel_policy, &refs, &n);
	if (err)
		goto out;
	if (!n) {
		NL_SET_ERR_MSG(info->extack, "no variable named");
		err = -EINVAL;
		goto out;
	}
	for (i = 0; i < n; i++)
		size += iec_var_msg_size(&refs[i], true);
	err = -ENOMEM;
	msg = genlmsg_new(size, GFP_KERNEL);
	if (!msg)
		goto out;
	err = -EMSGSIZE;
	hdr = genlmsg_put_reply(msg, info, &iec_nl_family, 0, IEC_CMD_VAR_GET);
	if (!hdr)
		goto out;
	for (i = 0; i < n; i++) {
		u32 len = iec_value_len(refs[i].desc);
		struct nlattr *nest, *val;

		err = -EMSGSIZE;
		nest = nla_nest_start(msg, IEC_A_VAR);
		if (!nest || iec_put_var(msg, &refs[i]))
			goto out;
		val = nla_reserve(msg, IEC_A_VALUE, len);
		if (!val)
			goto out;
		err = iec_var_read(&refs[i], nla_data(val), len);
		if (err)
			goto out;
		nla_nest_end(msg, nest);
	}
	genlmsg_end(msg, hdr);
	mutex_unlock(&iec_resources_lock);
	mutex_unlock(&iec_ctl_mutex);
	kfree(refs);
	return genlmsg_reply(msg, info);

out:
	mutex_unlock(&iec_resources_lock);
	mutex_unlock(&iec_ctl_mutex);
	nlmsg_free(msg);
	kfree(refs);
	return err;
}

/* Dump: one message per variable; cb->args: table (0 configuration,
 * 1.. the resources in order), index in it. */
static int iec_nl_var_list(struct sk_buff *skb, struct netlink_callback *cb)
{
	long table = cb->args[0], idx = cb->args[1];

	mutex_lock(&iec_ctl_mutex);
	mutex_lock(&iec_resources_lock);
	for (;; table++, idx = 0) {
		const struct iec_var_desc *vars = iec_cfg->vars;
		struct iec_resource *r = NULL;
		u32 n = iec_cfg->nvars;

		if (table > 0) {
			long k = 1;

			list_for_each_entry(r, &iec_resources, node)
				if (k++ == table)
					break;
			if (list_entry_is_head(r, &iec_resources, node))
				break;
			vars = r->vars;
			n = r->nvars;
		}
		for (; idx < n; idx++) {
			struct iec_var_ref ref;
			void *hdr;

			iec_var_ref_set(&ref, r, vars, idx);
			hdr = genlmsg_put(skb, NETLINK_CB(cb->skb).portid,
					  cb->nlh->nlmsg_seq, &iec_nl_family,
					  NLM_F_MULTI, IEC_CMD_VAR_LIST);
			if (!hdr)
				goto full;
			if (iec_put_var(skb, &ref)) {
				genlmsg_cancel(skb, hdr);
				goto full;
			}
			genlmsg_end(skb, hdr);
		}
	}
full:
	cb->args[0] = table;
	cb->args[1] = idx;
	mutex_unlock(&iec_resources_lock);
	mutex_unlock(&iec_ctl_mutex);
	return skb->len;
}

static int iec_nl_var_set(struct sk_buff *skb, struct genl_info *info)
{
	struct iec_var_ref *refs;
	u32 events[16];
	u32 n, i, nevents = 0;
	int err;

	mutex_lock(&iec_ctl_mutex);
	mutex_lock(&iec_resources_lock);
	err = iec_nl_vars(info, iec_nl_val_policy, &refs, &n);
	if (err)
		goto out;
	err = -EINVAL;
	if (!n) {
		NL_SET_ERR_MSG(info->extack, "no variable named");
		goto out;
	}
	/* everything is checked before anything is written */
	for (i = 0; i < n; i++) {
		err = iec_value_check(&refs[i], info->extack);
		if (err)
			goto out;
		if (!refs[i].desc->writable) {
			NL_SET_ERR_MSG(info->extack, "the variable is read-only");
			err = -EACCES;
			goto out;
		}
		if (iec_var_forced(&refs[i])) {
			NL_SET_ERR_MSG(info->extack, "the variable is forced");
			err = -EBUSY;
			goto out;
		}
	}
	/* the globals together: a task sees all of them or none */
	iec2kmod_image_lock();
	for (i = 0; i < n; i++) {
		const struct iec_var_desc *d = refs[i].desc;
		const void *v = nla_data(refs[i].value);

		if (refs[i].task)
			continue;
		if (iec_rises(d, v) && nevents < ARRAY_SIZE(events))
			events[nevents++] = d->single_event - 1;
		memcpy(d->addr, v, nla_len(refs[i].value));
	}
	iec2kmod_image_unlock();
	for (i = 0; i < nevents; i++)
		iec2kmod_event(events[i]);
	/* instance variables, each between two cycles of its task */
	err = 0;
	for (i = 0; i < n && !err; i++) {
		struct iec_task *t = refs[i].task;

		if (!t)
			continue;
		err = iec_task_boundary_copy(t, refs[i].desc->addr,
					     nla_data(refs[i].value),
					     nla_len(refs[i].value));
	}
	if (err)
		NL_SET_ERR_MSG(info->extack, "the task stays inside a cycle");
out:
	mutex_unlock(&iec_resources_lock);
	mutex_unlock(&iec_ctl_mutex);
	kfree(refs);
	return err;
}

static int iec_nl_var_force(struct sk_buff *skb, struct genl_info *info)
{
	struct iec_force **forces = NULL;
	struct iec_var_ref *refs;
	u32 n, i, added = 0;
	int err;

	mutex_lock(&iec_ctl_mutex);
	mutex_lock(&iec_resources_lock);
	err = iec_nl_vars(info, iec_nl_val_policy, &refs, &n);
	if (err)
		goto out;
	err = -EINVAL;
	if (!n) {
		NL_SET_ERR_MSG(info->extack, "no variable named");
		goto out;
	}
	for (i = 0; i < n; i++) {
		err = iec_value_check(&refs[i], info->extack);
		if (err)
			goto out;
		if (!iec_var_forced(&refs[i]))
			added++;
	}
	/* each force costs the tasks a copy at every cycle boundary */
	if (iec_forced_count() + added > IEC_NL_MAX_FORCES) {
		NL_SET_ERR_MSG(info->extack, "too many forced variables");
		err = -ENOSPC;
		goto out;
	}
	err = -ENOMEM;
	forces = kcalloc(n, sizeof(*forces), GFP_KERNEL);
	if (!forces)
		goto out;
	for (i = 0; i < n; i++) {
		u32 len = nla_len(refs[i].value);

		forces[i] = kzalloc(struct_size(forces[i], value, len), GFP_KERNEL);
		if (!forces[i])
			goto out;
		forces[i]->desc = refs[i].desc;
		forces[i]->res = refs[i].res;
		forces[i]->size = len;
		memcpy(forces[i]->value, nla_data(refs[i].value), len);
	}
	for (i = 0; i < n; i++) {
		struct iec_force *f = forces[i], *old;
		struct iec_task *t = refs[i].task;
		bool rise = false;

		if (t) {
			raw_spin_lock(&t->var_lock);
			old = iec_force_unlink(&t->forces, f->desc);
			f->next = t->forces;
			t->forces = f;
			if (!t->in_cycle)
				memcpy(f->desc->addr, f->value, f->size);
			t->ctx.sel_epoch++;	/* selective blocks: a new value */
			raw_spin_unlock(&t->var_lock);
		} else {
			iec2kmod_image_lock();
			old = iec_force_unlink(&iec_global_forces, f->desc);
			rise = iec_rises(f->desc, f->value);
			f->next = iec_global_forces;
			iec_global_forces = f;
			memcpy(f->desc->addr, f->value, f->size);
			iec2kmod_image_unlock();
		}
		forces[i] = NULL;
		kfree(old);
		if (rise)
			iec2kmod_event(f->desc->single_event - 1);
	}
	err = 0;
out:
	mutex_unlock(&iec_resources_lock);
	mutex_unlock(&iec_ctl_mutex);
	if (forces)
		for (i = 0; i < n; i++)
			kfree(forces[i]);
	kfree(forces);
	kfree(refs);
	return err;
}

static const struct nla_policy iec_nl_unforce_policy[IEC_A_MAX + 1] = {
	[IEC_A_VAR] = NLA_POLICY_NESTED(iec_nl_sel_policy),
	[IEC_A_ALL] = { .type = NLA_FLAG },
};

static int iec_nl_var_unforce(struct sk_buff *skb, struct genl_info *info)
{
	struct iec_force *drop = NULL, *f;
	struct iec_var_ref *refs = NULL;
	struct iec_resource *r;
	u32 n = 0, i;
	int err = 0;

	mutex_lock(&iec_ctl_mutex);
	mutex_lock(&iec_resources_lock);
	if (info->attrs[IEC_A_ALL]) {
		iec2kmod_image_lock();
		drop = iec_global_forces;
		iec_global_forces = NULL;
		iec2kmod_image_unlock();
		iec_forces_free(drop);
		list_for_each_entry(r, &iec_resources, node) {
			for (i = 0; i < r->ntasks; i++) {
				struct iec_task *t = &r->tasks[i];

				raw_spin_lock(&t->var_lock);
				drop = t->forces;
				t->forces = NULL;
				raw_spin_unlock(&t->var_lock);
				iec_forces_free(drop);
			}
		}
		goto out;
	}
	err = iec_nl_vars(info, iec_nl_sel_policy, &refs, &n);
	if (err)
		goto out;
	err = -EINVAL;
	if (!n) {
		NL_SET_ERR_MSG(info->extack, "no variable named (or ALL)");
		goto out;
	}
	for (i = 0; i < n; i++) {
		if (!iec_var_forced(&refs[i])) {
			NL_SET_ERR_MSG(info->extack, "the variable is not forced");
			err = -ENODATA;
			goto out;
		}
	}
	for (i = 0; i < n; i++) {
		struct iec_task *t = refs[i].task;

		if (t) {
			raw_spin_lock(&t->var_lock);
			f = iec_force_unlink(&t->forces, refs[i].desc);
			raw_spin_unlock(&t->var_lock);
		} else {
			iec2kmod_image_lock();
			f = iec_force_unlink(&iec_global_forces, refs[i].desc);
			iec2kmod_image_unlock();
		}
		kfree(f);
	}
	err = 0;
out:
	mutex_unlock(&iec_resources_lock);
	mutex_unlock(&iec_ctl_mutex);
	kfree(refs);
	return err;
}

/* The task "<resource>.<task>" names, or NULL; *r is its resource. */
static struct iec_task *iec_task_find(const char *name, struct iec_resource **r)
{
	const char *dot = strchr(name, '.');
	struct iec_resource *res;
	u32 i;

	if (!dot)
		return NULL;
	list_for_each_entry(res, &iec_resources, node) {
		if (strlen(res->name) != dot - name ||
		    strncasecmp(name, res->name, dot - name))
			continue;
		for (i = 0; i < res->ntasks; i++) {
			if (!strcasecmp(dot + 1, res->tasks[i].name)) {
				*r = res;
				return &res->tasks[i];
			}
		}
	}
	return NULL;
}

/*
 * start/stop one resource by name, or all of them (name NULL or "all");
 * start also takes one task, "<resource>.<task>" (a restart: the other
 * tasks of its resource are left as they are).
 * A stop returns once every task it stopped acknowledged (its thread is
 * idle: no cycle runs, the resource module may go), or -ETIMEDOUT after
 * the bound, naming the task that did not.
 */
static int iec_control_resource(const char *name, bool start, u32 run_ms)
{
	/* a common first release, late enough for every task to be asleep */
	ktime_t epoch = ktime_add_ms(ktime_get(), IEC_START_DELAY_MS);
	struct iec_resource *r;
	struct iec_task *t;
	unsigned long deadline;
	s64 longest = 0;
	int ret = -ENOENT;
	u32 i;

	if (name && !strcmp(name, "all"))
		name = NULL;
	mutex_lock(&iec_resources_lock);
	if (name && strchr(name, '.')) {
		t = iec_task_find(name, &r);
		if (t && start) {
			r->epoch = epoch;
			r->until = run_ms ? ktime_add_ms(epoch, run_ms) : 0;
			ret = r->start_task(r, t - r->tasks);
		} else if (t) {
			ret = -EOPNOTSUPP;	/* a stop is per resource */
		}
		mutex_unlock(&iec_resources_lock);
		return ret;
	}
	list_for_each_entry(r, &iec_resources, node) {
		if (name && strcasecmp(name, r->name))
			continue;
		if (start) {
			r->epoch = epoch;
			r->until = run_ms ? ktime_add_ms(epoch, run_ms) : 0;
			ret = r->start(r);
		} else {
			r->stop(r);
			for (i = 0; i < r->ntasks; i++)
				longest = max(longest, r->tasks[i].interval_ns);
			ret = 0;
		}
		if (ret)
			break;
	}
	if (!start && !ret) {
		deadline = jiffies + iec2kmod_wait_bound(longest);
		list_for_each_entry(r, &iec_resources, node) {
			if (name && strcasecmp(name, r->name))
				continue;
			ret = iec_wait_resource_idle(r, deadline);
			if (ret)
				break;
		}
	}
	if (!name && list_empty(&iec_resources))
		ret = 0;	/* "all" of nothing */
	mutex_unlock(&iec_resources_lock);
	return ret;
}

static int iec_nl_res(struct genl_info *info, bool start)
{
	const char *name = NULL;
	int err;

	if (info->attrs[IEC_A_NAME])
		name = nla_data(info->attrs[IEC_A_NAME]);
	mutex_lock(&iec_ctl_mutex);
	err = iec_control_resource(name, start, 0);
	mutex_unlock(&iec_ctl_mutex);
	if (err == -ENOENT)
		NL_SET_ERR_MSG_ATTR(info->extack, info->attrs[IEC_A_NAME],
				    "no such resource or task");
	else if (err == -EOPNOTSUPP)
		NL_SET_ERR_MSG_ATTR(info->extack, info->attrs[IEC_A_NAME],
				    "tasks are stopped by resource");
	else if (err == -ETIMEDOUT)
		NL_SET_ERR_MSG(info->extack,
			       "a task does not come back from its cycle (kernel log, status: in_cycle)");
	return err;
}

static int iec_nl_res_start(struct sk_buff *skb, struct genl_info *info)
{
	return iec_nl_res(info, true);
}

static int iec_nl_res_stop(struct sk_buff *skb, struct genl_info *info)
{
	return iec_nl_res(info, false);
}


static int iec_nl_slot_clear(struct sk_buff *skb, struct genl_info *info)
{
	long slot = -1;
	int err;

	if (info->attrs[IEC_A_SLOT_INDEX]) {
		slot = nla_get_u32(info->attrs[IEC_A_SLOT_INDEX]);
		if (slot >= iec_cfg->nslots) {
			NL_SET_ERR_MSG_ATTR(info->extack,
					    info->attrs[IEC_A_SLOT_INDEX],
					    "no such slot");
			return -ENOENT;
		}
	}
	mutex_lock(&iec_ctl_mutex);
	err = iec_gft_clear(slot);
	mutex_unlock(&iec_ctl_mutex);
	if (err == -ETIMEDOUT)
		NL_SET_ERR_MSG(info->extack,
			       "a task does not come back from its cycle (kernel log, status: in_cycle)");
	return err;
}

static long iec_nl_slot_arg(struct genl_info *info)
{
	long slot = -1;

	if (info->attrs[IEC_A_SLOT_INDEX]) {
		slot = nla_get_u32(info->attrs[IEC_A_SLOT_INDEX]);
		if (slot >= iec_cfg->nslots) {
			NL_SET_ERR_MSG_ATTR(info->extack,
					    info->attrs[IEC_A_SLOT_INDEX],
					    "no such slot");
			return -ENOENT;
		}
	}
	return slot;
}

/* The quick half of a swap: the staged builds replace the running ones. */
static int iec_nl_slot_publish(struct sk_buff *skb, struct genl_info *info)
{
	long slot = iec_nl_slot_arg(info);
	int err;

	if (slot < -1)
		return slot;
	mutex_lock(&iec_ctl_mutex);
	err = iec_gft_publish_staged(slot);
	mutex_unlock(&iec_ctl_mutex);
	if (err == -ENOENT)
		NL_SET_ERR_MSG(info->extack, "nothing is staged (insmod ... stage=1)");
	else if (err == -ETIMEDOUT)
		NL_SET_ERR_MSG(info->extack,
			       "published; a task does not come back from its cycle (the old body stays loaded)");
	return err < 0 ? err : 0;
}

static int iec_nl_slot_unstage(struct sk_buff *skb, struct genl_info *info)
{
	long slot = iec_nl_slot_arg(info);
	int err;

	if (slot < -1)
		return slot;
	mutex_lock(&iec_ctl_mutex);
	err = iec_gft_unstage(slot);
	mutex_unlock(&iec_ctl_mutex);
	return err;
}

/* commands that take no attribute at all */
static const struct nla_policy iec_nl_none_policy[IEC_A_MAX + 1] = {};

static const struct nla_policy iec_nl_get_policy[IEC_A_MAX + 1] = {
	[IEC_A_VAR] = NLA_POLICY_NESTED(iec_nl_sel_policy),
};

static const struct nla_policy iec_nl_set_policy[IEC_A_MAX + 1] = {
	[IEC_A_VAR] = NLA_POLICY_NESTED(iec_nl_val_policy),
};

static const struct nla_policy iec_nl_res_policy[IEC_A_MAX + 1] = {
	[IEC_A_NAME] = { .type = NLA_NUL_STRING, .len = 63 },
};

static const struct nla_policy iec_nl_status_policy[IEC_A_MAX + 1] = {
	[IEC_A_SLOTS_ONLY] = { .type = NLA_FLAG },
};

static const struct nla_policy iec_nl_slot_policy[IEC_A_MAX + 1] = {
	[IEC_A_SLOT_INDEX] = { .type = NLA_U32 },
};

static const struct genl_ops iec_nl_ops[] = {
	{
		.cmd = IEC_CMD_STATUS,
		.flags = GENL_ADMIN_PERM,
		.doit = iec_nl_status,
		.policy = iec_nl_status_policy,
		.maxattr = IEC_A_MAX,
	},
	{
		.cmd = IEC_CMD_VAR_GET,
		.flags = GENL_ADMIN_PERM,
		.doit = iec_nl_var_get,
		.policy = iec_nl_get_policy,
		.maxattr = IEC_A_MAX,
	},
	{
		.cmd = IEC_CMD_VAR_LIST,
		.flags = GENL_ADMIN_PERM,
		.dumpit = iec_nl_var_list,
		.policy = iec_nl_none_policy,
		.maxattr = IEC_A_MAX,
	},
	{
		.cmd = IEC_CMD_VAR_SET,
		.flags = GENL_ADMIN_PERM,
		.doit = iec_nl_var_set,
		.policy = iec_nl_set_policy,
		.maxattr = IEC_A_MAX,
	},
	{
		.cmd = IEC_CMD_VAR_FORCE,
		.flags = GENL_ADMIN_PERM,
		.doit = iec_nl_var_force,
		.policy = iec_nl_set_policy,
		.maxattr = IEC_A_MAX,
	},
	{
		.cmd = IEC_CMD_VAR_UNFORCE,
		.flags = GENL_ADMIN_PERM,
		.doit = iec_nl_var_unforce,
		.policy = iec_nl_unforce_policy,
		.maxattr = IEC_A_MAX,
	},
	{
		.cmd = IEC_CMD_RES_START,
		.flags = GENL_ADMIN_PERM,
		.doit = iec_nl_res_start,
		.policy = iec_nl_res_policy,
		.maxattr = IEC_A_MAX,
	},
	{
		.cmd = IEC_CMD_RES_STOP,
		.flags = GENL_ADMIN_PERM,
		.doit = iec_nl_res_stop,
		.policy = iec_nl_res_policy,
		.maxattr = IEC_A_MAX,
	},
	{
		.cmd = IEC_CMD_SLOT_CLEAR,
		.flags = GENL_ADMIN_PERM,
		.doit = iec_nl_slot_clear,
		.policy = iec_nl_slot_policy,
		.maxattr = IEC_A_MAX,
	},
	{
		.cmd = IEC_CMD_SLOT_PUBLISH,
		.flags = GENL_ADMIN_PERM,
		.doit = iec_nl_slot_publish,
		.policy = iec_nl_slot_policy,
		.maxattr = IEC_A_MAX,
	},
	{
		.cmd = IEC_CMD_SLOT_UNSTAGE,
		.flags = GENL_ADMIN_PERM,
		.doit = iec_nl_slot_unstage,
		.policy = iec_nl_slot_policy,
		.maxattr = IEC_A_MAX,
	},
};

/* netnsok stays 0: the family exists in the initial namespace only */
static struct genl_family iec_nl_family = {
	.name = IEC_NL_FAMILY,
	.version = IEC_NL_VERSION,
	.maxattr = IEC_A_MAX,
	.parallel_ops = true,
	.module = THIS_MODULE,
	.ops = iec_nl_ops,
	.n_ops = ARRAY_SIZE(iec_nl_ops),
};

/* ------------------------------------------------------------------ */
/* sysfs                                                              */
/* ------------------------------------------------------------------ */

/* Appends to a sysfs page; a status longer than a page ends in "...". */
static __printf(3, 4) void iec_emit(char *buf, int *len, const char *fmt, ...)
{
	va_list args;

	if (*len >= PAGE_SIZE - 5)
		return;
	va_start(args, fmt);
	*len += vscnprintf(buf + *len, PAGE_SIZE - 4 - *len, fmt, args);
	va_end(args);
	if (*len >= PAGE_SIZE - 5)
		*len += scnprintf(buf + *len, PAGE_SIZE - *len, "...\n");
}

static ssize_t status_show(struct kobject *kobj, struct kobj_attribute *attr,
			   char *buf)
{
	struct iec_resource *r;
	int len = 0;
	u32 i;

	iec_emit(buf, &len, "configuration %s source %s interface %s\n",
		 iec_cfg->name, iec_cfg->source_hash, iec_cfg->iface_hash);
	mutex_lock(&iec_resources_lock);
	list_for_each_entry(r, &iec_resources, node) {
		iec_emit(buf, &len, "resource %s module %s cpu %d\n",
			 r->name, module_name(r->owner), r->cpu);
		for (i = 0; i < r->ntasks; i++) {
			struct iec_task *t = &r->tasks[i];
			struct iec_task_stats *s = &t->stats;
			int st = READ_ONCE(t->state);

			iec_emit(buf, &len,
				 "task %s.%s state %s interval_ns %lld priority %d cycles %llu overruns %llu exec_min_ns %lld exec_max_ns %lld exec_avg_ns %lld latency_max_ns %lld faults %llu fault %s pou %s line %d in_cycle_ms %lld starts %llu\n",
				 r->name, t->name,
				 st >= 0 && st <= IEC_TASK_FAULT ? iec_state_names[st] : "?",
				 t->interval_ns, t->priority, s->cycles,
				 s->overruns, s->exec_min_ns, s->exec_max_ns,
				 s->cycles ? div64_s64(s->exec_sum_ns, s->cycles) : 0,
				 s->latency_max_ns, s->faults,
				 s->fault_code ? iec_fault_name(s->fault_code) : "none",
				 s->fault_code ? s->fault_pou_name : "-",
				 s->fault_line,
				 (smp_load_acquire(&t->cycle_seq) & 1) ?
				 ktime_ms_delta(ktime_get(), READ_ONCE(t->cycle_start)) : -1LL,
				 s->starts);
		}
	}
	mutex_unlock(&iec_resources_lock);
	for (i = 0; i < iec_cfg->nslots; i++) {
		struct iec_gft_slot *slot = &iec_cfg->slots[i];
		struct iec_program_type *p;

		rcu_read_lock();	/* see iec_put_slot() */
		p = rcu_dereference_raw(slot->cur);
		iec_emit(buf, &len,
			 "slot %u %s interface %016llx module %s build %s since %lld publications %llu\n",
			 i, slot->type_name, slot->iface_hash,
			 p ? module_name(p->owner) : "-",
			 p ? p->build_id : "-",
			 ktime_to_ns(slot->since), slot->publications);
		rcu_read_unlock();
	}
	return len;
}

static ssize_t control_store(struct kobject *kobj, struct kobj_attribute *attr,
			     const char *buf, size_t count)
{
	char cmd[16], arg[64];
	int ret, n;
	u32 slot, run_ms = 0;

	n = sscanf(buf, "%15s %63s %u", cmd, arg, &run_ms);
	if (n < 2 || (n == 3) != !strcmp(cmd, "run") || (n == 3 && !run_ms))
		return -EINVAL;
	mutex_lock(&iec_ctl_mutex);
	if (!strcmp(cmd, "start") || !strcmp(cmd, "stop")) {
		ret = iec_control_resource(arg, cmd[2] == 'a', 0);
	} else if (!strcmp(cmd, "run")) {
		ret = iec_control_resource(arg, true, run_ms);
	} else if (!strcmp(cmd, "clear")) {
		if (!strcmp(arg, "all")) {
			ret = iec_gft_clear(-1);
		} else {
			ret = kstrtou32(arg, 10, &slot);
			if (!ret)
				ret = iec_gft_clear(slot);
		}
	} else {
		ret = -EINVAL;
	}
	mutex_unlock(&iec_ctl_mutex);
	return ret ? ret : count;
}

static struct kobj_attribute status_attr = __ATTR(status, 0400, status_show, NULL);
static struct kobj_attribute control_attr = __ATTR(control, 0200, NULL, control_store);

static struct attribute *iec_attrs[] = {
	&status_attr.attr,
	&control_attr.attr,
	NULL,
};

static const struct attribute_group iec_group = {
	.attrs = iec_attrs,
};

int iec_ctl_init(void)
{
	int ret;

	iec_root_kobj = kobject_create_and_add("iec2kmod", kernel_kobj);
	if (!iec_root_kobj)
		return -ENOMEM;
	iec_cfg_kobj = kobject_create_and_add(iec_cfg->name, iec_root_kobj);
	if (!iec_cfg_kobj) {
		ret = -ENOMEM;
		goto err_root;
	}
	ret = sysfs_create_group(iec_cfg_kobj, &iec_group);
	if (ret)
		goto err_cfg;
	ret = genl_register_family(&iec_nl_family);
	if (ret) {
		pr_err("iec2kmod: generic netlink family %s: error %d\n",
		       IEC_NL_FAMILY, ret);
		goto err_group;
	}
	return 0;

err_group:
	sysfs_remove_group(iec_cfg_kobj, &iec_group);
err_cfg:
	kobject_put(iec_cfg_kobj);
err_root:
	kobject_put(iec_root_kobj);
	return ret;
}

void iec_ctl_exit(void)
{
	genl_unregister_family(&iec_nl_family);
	sysfs_remove_group(iec_cfg_kobj, &iec_group);
	kobject_put(iec_cfg_kobj);
	kobject_put(iec_root_kobj);
	/* no resource is left: only forced configuration globals remain */
	iec_forces_free(iec_global_forces);
	iec_global_forces = NULL;
}
