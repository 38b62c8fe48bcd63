// SPDX-License-Identifier: GPL-2.0-only OR MIT
/*
 * iec_ctl_nl.c - the generic netlink family "iec2kmod" (iec_nl.h) of the
 * configuration's control plane, for plc-manager: status, resource (or
 * task) start, resource stop, slot clear, publish and unstage, and the
 * command table with the variable commands of iec_vars.c (list, read,
 * write, force, unforce).
 *
 * Every command needs CAP_NET_ADMIN in the initial namespace (the read
 * commands: or monitor_gid, iec_ctl.c) and is checked strictly against its
 * own policy.  Commands run one at a time (iec_ctl_mutex); they may sleep,
 * but never while holding a raw lock.  iec_ctl_init() registers the family.
 */
#include <linux/capability.h>
#include <linux/module.h>
#include <linux/mutex.h>
#include <linux/rcupdate.h>
#include <linux/string.h>
#include <linux/timekeeping.h>
#include <net/genetlink.h>

#include "iec_kmod.h"
#include "iec_ctl.h"
#include "iec_nl.h"

/*
 * The read commands (STATUS, VAR_GET, VAR_LIST): CAP_NET_ADMIN as for
 * GENL_ADMIN_PERM (of the sender and of the socket's opener), or the
 * monitor group.
 */
int iec_nl_may_read(const struct sk_buff *skb)
{
	return netlink_capable(skb, CAP_NET_ADMIN) || iec_monitor() ? 0 : -EPERM;
}

static int iec_nl_var_list_start(struct netlink_callback *cb)
{
	return iec_nl_may_read(cb->skb);
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
	    nla_put_s64(skb, IEC_A_STARTED_NS, ktime_to_ns(s->started), IEC_A_PAD) ||
	    nla_put_s64(skb, IEC_A_LAST_END_NS, ktime_to_ns(READ_ONCE(s->last_end)),
			IEC_A_PAD))
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

/*
 * One GFT slot; the caller holds iec_resources_lock.  A slot's program type
 * lives in its module.  The reference is read under rcu_read_lock(): a
 * replaced module is freed only after the synchronize_rcu() of module
 * removal, so what we read stays valid.
 */
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
	int err = iec_nl_may_read(skb);

	if (err)
		return err;
	err = -EMSGSIZE;
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

static int iec_nl_res(struct genl_info *info, bool start)
{
	const char *name = NULL;
	int err;

	err = iec_nla_strict_string(info->attrs[IEC_A_NAME], info->extack);
	if (err)
		return err;
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

/* The slot a SLOT_* command names, -1 for every slot, or -ENOENT */
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

static int iec_nl_slot_clear(struct sk_buff *skb, struct genl_info *info)
{
	long slot = iec_nl_slot_arg(info);
	int err;

	if (slot < -1)
		return slot;
	mutex_lock(&iec_ctl_mutex);
	err = iec_gft_clear(slot);
	mutex_unlock(&iec_ctl_mutex);
	if (err == -ETIMEDOUT)
		NL_SET_ERR_MSG(info->extack,
			       "a task does not come back from its cycle (kernel log, status: in_cycle)");
	return err;
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
	/* the read commands check iec_nl_may_read() themselves */
	{
		.cmd = IEC_CMD_STATUS,
		.doit = iec_nl_status,
		.policy = iec_nl_status_policy,
		.maxattr = IEC_A_MAX,
	},
	{
		.cmd = IEC_CMD_VAR_GET,
		.doit = iec_nl_var_get,
		.policy = iec_nl_get_policy,
		.maxattr = IEC_A_MAX,
	},
	{
		.cmd = IEC_CMD_VAR_LIST,
		.start = iec_nl_var_list_start,
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
struct genl_family iec_nl_family = {
	.name = IEC_NL_FAMILY,
	.version = IEC_NL_VERSION,
	.maxattr = IEC_A_MAX,
	.parallel_ops = true,
	.module = THIS_MODULE,
	.ops = iec_nl_ops,
	.n_ops = ARRAY_SIZE(iec_nl_ops),
};
