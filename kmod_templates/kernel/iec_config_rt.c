// SPDX-License-Identifier: GPL-2.0-only OR MIT
/*
 * iec_config_rt.c - the configuration module's runtime: the image lock,
 * the Global Function Table, resource registration and event wake-ups.
 *
 * GFT protocol (seed 000, hot code change):
 *  - a slot holds an RCU pointer to the program type it runs and a module
 *    reference on that type's module, so a body in use cannot be unloaded;
 *  - bodies run only inside task cycles, which both ends mark under the
 *    task's var_lock (cycle_seq, iec2kmod_cycle_begin/end): the cycles are
 *    the read-side critical sections;
 *  - publishing a new type: check the interface hash, take a reference on
 *    the new module, rcu_replace_pointer, then a grace period: wait until
 *    every cycle that was running at the replacement in a task that runs
 *    the slot (iec_task.slots) has ended (a later cycle sees the new
 *    pointer: the var_lock orders it), then drop the old module's
 *    reference;
 *  - clearing a slot (manager, before removing a program module) does the
 *    same with NULL;
 *  - a swap in two halves: a build inserted with stage=1 only waits in its
 *    slot (checked, referenced); IEC_CMD_SLOT_PUBLISH later replaces the
 *    pointer (the next cycle of every task runs it), then the grace
 *    period.  The slow half (insmod: relocation, checks) is out of the
 *    publication's path.
 *
 * The grace period is our own, not synchronize_srcu(): a PLC cycle may be
 * long, and a task whose body never returns (a thread that died inside
 * it) would make an SRCU grace period endless, with the manager blocked
 * in it.  Ours waits with a bound (iec2kmod_wait_bound()) and can name
 * the task that does not come back.  When the bound passes, the old body
 * stays "retired" on its slot with its module reference (the module
 * cannot be removed: no use-after-free), the command fails with
 * -ETIMEDOUT, and the next publication or clear of the slot tries again.
 */
#include <linux/jiffies.h>
#include <linux/kernel.h>
#include <linux/moduleparam.h>
#include <linux/module.h>
#include <linux/mutex.h>
#include <linux/sched.h>
#include <linux/spinlock.h>
#include <linux/timekeeping.h>
#include <linux/wait.h>
#include <asm/fpu/api.h>

#include "iec_kmod.h"

struct iec_config *iec_cfg;
LIST_HEAD(iec_resources);
DEFINE_MUTEX(iec_resources_lock);

static DEFINE_RAW_SPINLOCK(iec_image_raw_lock);
static DEFINE_MUTEX(iec_gft_mutex);	/* serialises publications */

/* woken by the tasks at the end of a cycle and when they go idle */
DECLARE_WAIT_QUEUE_HEAD(iec_ack_wq);

static unsigned int wait_ms = 1000;
module_param(wait_ms, uint, 0644);
MODULE_PARM_DESC(wait_ms,
		 "longest wait for a task (stop, slot clear, publication), in ms, plus four task periods (default 1000)");

unsigned long iec2kmod_wait_bound(s64 interval_ns)
{
	u64 ns = (u64)clamp_t(unsigned int, READ_ONCE(wait_ms), 10, 600000) *
		 NSEC_PER_MSEC;

	if (interval_ns > 0)
		ns += 4 * min_t(u64, interval_ns, 60ULL * NSEC_PER_SEC);
	return nsecs_to_jiffies(ns) + 1;
}
EXPORT_SYMBOL_GPL(iec2kmod_wait_bound);

void iec2kmod_task_idle(struct iec_task *t)
{
	smp_store_release(&t->active, false);
	if (wq_has_sleeper(&iec_ack_wq))
		wake_up_all(&iec_ack_wq);
}
EXPORT_SYMBOL_GPL(iec2kmod_task_idle);

/* Names a task that did not come back within the bound. */
void iec_task_stuck_report(const char *what, struct iec_resource *r,
			   struct iec_task *t)
{
	unsigned long seq = smp_load_acquire(&t->cycle_seq);

	if (seq & 1)
		pr_err("iec2kmod: %s: task %s.%s does not come back: inside one cycle for %lld ms\n",
		       what, r->name, t->name,
		       ktime_ms_delta(ktime_get(), READ_ONCE(t->cycle_start)));
	else
		pr_err("iec2kmod: %s: task %s.%s does not come back: it does not acknowledge\n",
		       what, r->name, t->name);
}

void iec2kmod_image_lock(void)
	__acquires(iec_image_lock)
{
	raw_spin_lock(&iec_image_raw_lock);
}
EXPORT_SYMBOL_GPL(iec2kmod_image_lock);

void iec2kmod_image_unlock(void)
	__releases(iec_image_lock)
{
	raw_spin_unlock(&iec_image_raw_lock);
}
EXPORT_SYMBOL_GPL(iec2kmod_image_unlock);

/* Called by a task inside its cycle: the cycle is the read-side section. */
int iec2kmod_run_program(u32 slot, void *self, struct iec_ctx *ctx)
{
	struct iec_program_type *type;
	int ret = 0;

	if (slot >= iec_cfg->nslots)
		return -EINVAL;
	type = rcu_dereference_raw(iec_cfg->slots[slot].cur);
	/* a task's programs run on its own ctx (iec_task_cycle()) */
	if (type && unlikely(!READ_ONCE(type->first_run_ns)) &&
	    !cmpxchg64(&type->first_run_ns, 0, ktime_get_real_ns()))
		WRITE_ONCE(type->first_run_task,
			   container_of(ctx, struct iec_task, ctx)->task_id + 1);
	if (!type) {
		ret = -ENOENT;
	} else if (type->uses_fpu) {
		kernel_fpu_begin();
		type->body(self, ctx);
		kernel_fpu_end();
	} else {
		type->body(self, ctx);
	}
	if (!ret && ctx->fault != IEC_FAULT_NONE)
		ret = -ENODATA;
	return ret;
}
EXPORT_SYMBOL_GPL(iec2kmod_run_program);

static int iec_gft_find(const char *name)
{
	u32 i;

	for (i = 0; i < iec_cfg->nslots; i++)
		if (!strcmp(iec_cfg->slots[i].type_name, name))
			return i;
	return -1;
}

static bool iec_gp_passed(void)
{
	struct iec_resource *r;
	u32 i;

	list_for_each_entry(r, &iec_resources, node) {
		for (i = 0; i < r->ntasks; i++) {
			struct iec_task *t = &r->tasks[i];

			if ((t->gp_snap & 1) &&
			    smp_load_acquire(&t->cycle_seq) == t->gp_snap)
				return false;
		}
	}
	return true;
}

/* Whether @t's programs run the body of slot @only (-1: any slot). */
static bool iec_task_runs_slot(const struct iec_task *t, long only)
{
	u32 i;

	if (only < 0)
		return true;
	for (i = 0; i < t->nslots; i++)
		if (t->slots[i] == only)
			return true;
	return false;
}

/*
 * The grace period: waits until every task cycle running now that may
 * run a body of slot @only (-1: of any slot) has ended, at most the bound
 * of the slowest such task.  A task that runs none of the slot's bodies
 * cannot hold a pointer to one: it is not waited for.  -ETIMEDOUT (after
 * naming the task) if one did not end.  The caller holds iec_gft_mutex.
 */
static int iec_gft_grace_period(const char *what, long only)
{
	struct iec_resource *r;
	s64 longest = -1;
	int ret = 0;
	u32 i;

	mutex_lock(&iec_resources_lock);
	list_for_each_entry(r, &iec_resources, node) {
		for (i = 0; i < r->ntasks; i++) {
			struct iec_task *t = &r->tasks[i];

			/* the lock orders the replaced pointer before the
			 * task's next cycle_begin, or that begin before us */
			if (!iec_task_runs_slot(t, only)) {
				t->gp_snap = 0;		/* even: not waited for */
				continue;
			}
			raw_spin_lock(&t->var_lock);
			t->gp_snap = t->cycle_seq;
			raw_spin_unlock(&t->var_lock);
			if (t->gp_snap & 1)
				longest = max(longest, t->interval_ns);
		}
	}
	if (longest >= 0 &&
	    !wait_event_timeout(iec_ack_wq, iec_gp_passed(),
				iec2kmod_wait_bound(longest))) {
		ret = -ETIMEDOUT;
		list_for_each_entry(r, &iec_resources, node)
			for (i = 0; i < r->ntasks; i++)
				if ((r->tasks[i].gp_snap & 1) &&
				    smp_load_acquire(&r->tasks[i].cycle_seq) ==
				    r->tasks[i].gp_snap)
					iec_task_stuck_report(what, r, &r->tasks[i]);
	}
	mutex_unlock(&iec_resources_lock);
	return ret;
}

/*
 * Drops the references of the retired bodies of slot @only (-1: of every
 * slot) after one grace period.  The caller holds iec_gft_mutex.
 */
static int iec_gft_sync(long only, const char *what)
{
	struct iec_program_type *p;
	bool any = false;
	int ret;
	u32 i;

	lockdep_assert_held(&iec_gft_mutex);
	for (i = 0; i < iec_cfg->nslots; i++)
		if ((only < 0 || i == only) && iec_cfg->slots[i].retired)
			any = true;
	if (!any)
		return 0;
	ret = iec_gft_grace_period(what, only);
	for (i = 0; i < iec_cfg->nslots; i++) {
		struct iec_gft_slot *slot = &iec_cfg->slots[i];

		if ((only >= 0 && i != only) || !slot->retired)
			continue;
		if (ret) {
			pr_err("iec2kmod: slot %s: %s stays loaded until that cycle ends\n",
			       slot->type_name, module_name(slot->retired->owner));
			continue;
		}
		/* no task runs a retired body any more: their modules may go */
		while ((p = slot->retired)) {
			slot->retired = p->retired_next;
			p->retired_next = NULL;
			module_put(p->owner);
		}
	}
	return ret;
}

/* Puts @new into the slot, the old body on its retired list. */
static void iec_gft_replace(struct iec_gft_slot *slot,
			    struct iec_program_type *new)
{
	struct iec_program_type *old;

	old = rcu_replace_pointer(slot->cur, new,
				  lockdep_is_held(&iec_gft_mutex));
	if (old) {
		old->retired_next = slot->retired;
		slot->retired = old;
	}
	slot->since = ktime_get_real();
	slot->publications++;
}

/* The slot of @type if its interface matches, else a negative errno. */
static int iec_gft_slot_of(struct iec_program_type *type)
{
	int i;

	if (!iec_cfg)
		return -ENODEV;
	i = iec_gft_find(type->type_name);
	if (i < 0) {
		pr_err("iec2kmod: %s: program type %s is not used by configuration %s\n",
		       module_name(type->owner), type->type_name, iec_cfg->name);
		return -ENOENT;
	}
	if (iec_cfg->slots[i].iface_hash != type->iface_hash) {
		pr_err("iec2kmod: %s: interface %016llx of %s does not match slot %016llx\n",
		       module_name(type->owner), type->iface_hash,
		       type->type_name, iec_cfg->slots[i].iface_hash);
		return -EPROTO;
	}
	return i;
}

int iec2kmod_gft_stage(struct iec_program_type *type)
{
	struct iec_gft_slot *slot;
	int i = iec_gft_slot_of(type);

	if (i < 0)
		return i;
	slot = &iec_cfg->slots[i];
	mutex_lock(&iec_gft_mutex);
	if (slot->staged) {
		mutex_unlock(&iec_gft_mutex);
		pr_err("iec2kmod: %s: slot %s has %s staged already\n",
		       module_name(type->owner), slot->type_name,
		       module_name(slot->staged->owner));
		return -EBUSY;
	}
	/* the caller is the module's own init: it cannot go away meanwhile */
	__module_get(type->owner);
	slot->staged = type;
	mutex_unlock(&iec_gft_mutex);
	pr_info("iec2kmod: slot %s: %s (%s) staged\n", type->type_name,
		module_name(type->owner), type->build_id);
	return 0;
}
EXPORT_SYMBOL_GPL(iec2kmod_gft_stage);

/*
 * Publishes the staged build of slot @i (-1: of every slot that has one)
 * and waits one grace period for the replaced bodies.  The number of
 * slots published, or -ENOENT when none was staged, or -ETIMEDOUT (the
 * new bodies run all the same, see iec_gft_sync()).
 */
int iec_gft_publish_staged(long i)
{
	int n = 0;
	int ret;
	u32 k;

	if (!iec_cfg || i >= (long)iec_cfg->nslots)
		return -EINVAL;
	mutex_lock(&iec_gft_mutex);
	for (k = 0; k < iec_cfg->nslots; k++) {
		struct iec_gft_slot *slot = &iec_cfg->slots[k];

		if ((i >= 0 && k != i) || !slot->staged)
			continue;
		iec_gft_replace(slot, slot->staged);
		slot->staged = NULL;
		n++;
	}
	ret = n ? iec_gft_sync(i, "publish") : -ENOENT;
	mutex_unlock(&iec_gft_mutex);
	return ret ? ret : n;
}

/* Drops the staged builds of slot @i (-1: of every slot), unpublished. */
int iec_gft_unstage(long i)
{
	u32 k;

	if (!iec_cfg || i >= (long)iec_cfg->nslots)
		return -EINVAL;
	mutex_lock(&iec_gft_mutex);
	for (k = 0; k < iec_cfg->nslots; k++) {
		struct iec_gft_slot *slot = &iec_cfg->slots[k];

		if ((i < 0 || k == i) && slot->staged) {
			module_put(slot->staged->owner);
			slot->staged = NULL;
		}
	}
	mutex_unlock(&iec_gft_mutex);
	return 0;
}

int iec2kmod_gft_publish(struct iec_program_type *type)
{
	struct iec_gft_slot *slot;
	int i = iec_gft_slot_of(type);

	if (i < 0)
		return i;
	slot = &iec_cfg->slots[i];
	/* the caller is the module's own init: it cannot go away meanwhile */
	__module_get(type->owner);
	mutex_lock(&iec_gft_mutex);
	/*
	 * Published even if the grace period times out: the new body runs
	 * from the next cycle on, the old one stays retired (loaded).  A
	 * failed init would free a module the slot points to.
	 */
	iec_gft_replace(slot, type);
	iec_gft_sync(i, "publish");
	mutex_unlock(&iec_gft_mutex);
	pr_info("iec2kmod: slot %s now runs %s (%s)\n", type->type_name,
		module_name(type->owner), type->build_id);
	return 0;
}
EXPORT_SYMBOL_GPL(iec2kmod_gft_publish);

/*
 * Empties slot @i (-1: every slot), with one grace period.  -ETIMEDOUT if
 * a task stays inside a cycle that may run an old body: the slots are
 * empty all the same, the old bodies' modules stay loaded.
 */
int iec_gft_clear(long i)
{
	u32 k;
	int ret;

	if (!iec_cfg || i >= (long)iec_cfg->nslots)
		return -EINVAL;
	iec_gft_unstage(i);	/* a staged build goes with the slot */
	mutex_lock(&iec_gft_mutex);
	for (k = 0; k < iec_cfg->nslots; k++)
		if ((i < 0 || k == i) && rcu_access_pointer(iec_cfg->slots[k].cur))
			iec_gft_replace(&iec_cfg->slots[k], NULL);
	ret = iec_gft_sync(i, "clear");
	mutex_unlock(&iec_gft_mutex);
	return ret;
}

static bool iec_resource_idle(struct iec_resource *res, struct iec_task **busy)
{
	u32 i;

	for (i = 0; i < res->ntasks; i++) {
		if (smp_load_acquire(&res->tasks[i].active)) {
			*busy = &res->tasks[i];
			return false;
		}
	}
	return true;
}

/*
 * After res->stop(): waits until every task of @res acknowledged (its
 * thread went idle), until @deadline (jiffies) at most.  -ETIMEDOUT names
 * the task that did not.
 */
int iec_wait_resource_idle(struct iec_resource *res, unsigned long deadline)
{
	struct iec_task *busy = NULL;
	long left = max_t(long, (long)(deadline - jiffies), 1);

	smp_mb();	/* the stop request before reading active */
	if (wait_event_timeout(iec_ack_wq, iec_resource_idle(res, &busy), left))
		return 0;
	iec_task_stuck_report("stop", res, busy);
	return -ETIMEDOUT;
}

int iec2kmod_register_resource(struct iec_resource *res)
{
	struct iec_resource *r;

	if (!iec_cfg)
		return -ENODEV;
	mutex_lock(&iec_resources_lock);
	list_for_each_entry(r, &iec_resources, node) {
		if (!strcmp(r->name, res->name)) {
			mutex_unlock(&iec_resources_lock);
			return -EEXIST;
		}
	}
	list_add_tail_rcu(&res->node, &iec_resources);
	mutex_unlock(&iec_resources_lock);
	return 0;
}
EXPORT_SYMBOL_GPL(iec2kmod_register_resource);

void iec2kmod_unregister_resource(struct iec_resource *res)
{
	mutex_lock(&iec_resources_lock);
	list_del_rcu(&res->node);
	mutex_unlock(&iec_resources_lock);
	/* a command still waiting for one of its tasks' cycle boundaries */
	wait_event(iec_ack_wq, !atomic_read(&res->users));
	synchronize_rcu();	/* iec2kmod_event() walks the list under RCU */
}
EXPORT_SYMBOL_GPL(iec2kmod_unregister_resource);

/*
 * Wakes the event tasks of a SINGLE variable.  Called outside the image
 * lock from a task's copy-out or from a manager write; the resource list
 * is walked under RCU so a real-time caller never sleeps here.
 */
void iec2kmod_event(u32 event)
{
	struct iec_resource *r;
	u32 i;

	rcu_read_lock();
	list_for_each_entry_rcu(r, &iec_resources, node) {
		for (i = 0; i < r->ntasks; i++) {
			struct iec_task *t = &r->tasks[i];

			if (t->single_event != (int)event || !t->thread)
				continue;
			WRITE_ONCE(t->event_pending, true);
			wake_up_process(t->thread);
		}
	}
	rcu_read_unlock();
}
EXPORT_SYMBOL_GPL(iec2kmod_event);

int iec_config_init(struct iec_config *cfg)
{
	iec_cfg = cfg;
	return iec_ctl_init();
}

void iec_config_exit(struct iec_config *cfg)
{
	u32 i;

	iec_ctl_exit();
	/* program modules hold references on us: none is left here */
	for (i = 0; i < cfg->nslots; i++)
		WARN_ON_ONCE(rcu_access_pointer(cfg->slots[i].cur) ||
			     cfg->slots[i].retired || cfg->slots[i].staged);
	iec_cfg = NULL;
}
