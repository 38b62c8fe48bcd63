// SPDX-License-Identifier: GPL-2.0-only OR MIT
/*
 * iec_config_rt.c - the configuration module's runtime: the image lock,
 * the Global Function Table, resource registration and event wake-ups.
 *
 * GFT protocol (seed 000, hot code change):
 *  - a slot holds an RCU pointer to the program type it runs and a module
 *    reference on that type's module, so a body in use cannot be unloaded;
 *  - tasks call bodies inside an SRCU read section (a PLC cycle may be
 *    long: SRCU keeps it out of the global RCU grace periods);
 *  - publishing a new type: check the interface hash, take a reference on
 *    the new module, rcu_assign_pointer, synchronize_srcu (no task can
 *    still be running the old body), drop the old module's reference;
 *  - clearing a slot (manager, before removing a program module) does the
 *    same with NULL.
 */
#include <linux/kernel.h>
#include <linux/module.h>
#include <linux/mutex.h>
#include <linux/sched.h>
#include <linux/spinlock.h>
#include <linux/srcu.h>
#include <linux/timekeeping.h>
#include <asm/fpu/api.h>

#include "iec_kmod.h"

struct iec_config *iec_cfg;
LIST_HEAD(iec_resources);
DEFINE_MUTEX(iec_resources_lock);

static DEFINE_RAW_SPINLOCK(iec_image_raw_lock);
DEFINE_STATIC_SRCU(iec_gft_srcu);
static DEFINE_MUTEX(iec_gft_mutex);	/* serialises publications */

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

int iec2kmod_run_program(u32 slot, void *self, struct iec_ctx *ctx)
{
	struct iec_program_type *type;
	int idx, ret = 0;

	if (slot >= iec_cfg->nslots)
		return -EINVAL;
	idx = srcu_read_lock(&iec_gft_srcu);
	type = srcu_dereference(iec_cfg->slots[slot].cur, &iec_gft_srcu);
	if (!type) {
		ret = -ENOENT;
	} else if (type->uses_fpu) {
		kernel_fpu_begin();
		type->body(self, ctx);
		kernel_fpu_end();
	} else {
		type->body(self, ctx);
	}
	srcu_read_unlock(&iec_gft_srcu, idx);
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

/* Replaces the body of a slot; the caller holds iec_gft_mutex. */
static void iec_gft_replace(struct iec_gft_slot *slot,
			    struct iec_program_type *new)
{
	struct iec_program_type *old;

	old = rcu_replace_pointer(slot->cur, new,
				  lockdep_is_held(&iec_gft_mutex));
	synchronize_srcu(&iec_gft_srcu);
	/* no task runs the old body any more: its module may go */
	if (old)
		module_put(old->owner);
	slot->since = ktime_get_real();
	slot->publications++;
}

int iec2kmod_gft_publish(struct iec_program_type *type)
{
	struct iec_gft_slot *slot;
	int i;

	if (!iec_cfg)
		return -ENODEV;
	i = iec_gft_find(type->type_name);
	if (i < 0) {
		pr_err("iec2kmod: %s: program type %s is not used by configuration %s\n",
		       module_name(type->owner), type->type_name, iec_cfg->name);
		return -ENOENT;
	}
	slot = &iec_cfg->slots[i];
	if (slot->iface_hash != type->iface_hash) {
		pr_err("iec2kmod: %s: interface %016llx of %s does not match slot %016llx\n",
		       module_name(type->owner), type->iface_hash,
		       type->type_name, slot->iface_hash);
		return -EPROTO;
	}
	/* the caller is the module's own init: it cannot go away meanwhile */
	__module_get(type->owner);
	mutex_lock(&iec_gft_mutex);
	iec_gft_replace(slot, type);
	mutex_unlock(&iec_gft_mutex);
	pr_info("iec2kmod: slot %s now runs %s (%s)\n", type->type_name,
		module_name(type->owner), type->build_id);
	return 0;
}
EXPORT_SYMBOL_GPL(iec2kmod_gft_publish);

int iec_gft_clear(u32 i)
{
	if (!iec_cfg || i >= iec_cfg->nslots)
		return -EINVAL;
	mutex_lock(&iec_gft_mutex);
	if (rcu_access_pointer(iec_cfg->slots[i].cur))
		iec_gft_replace(&iec_cfg->slots[i], NULL);
	mutex_unlock(&iec_gft_mutex);
	return 0;
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
	/* resource modules hold references on us: none is left here */
	for (i = 0; i < cfg->nslots; i++)
		WARN_ON_ONCE(rcu_access_pointer(cfg->slots[i].cur));
	iec_cfg = NULL;
}
