// SPDX-License-Identifier: GPL-2.0-only OR MIT
/*
 * iec_ctl.c - the configuration's control plane: sysfs.
 *
 *   /sys/kernel/iec2kmod/<configuration>/status    resources, tasks, slots
 *   /sys/kernel/iec2kmod/<configuration>/control   "start <resource>|all",
 *                                                   "stop <resource>|all",
 *                                                   "clear <slot>|all"
 * Both are root-only (0400 / 0200).
 */
#include <linux/kobject.h>
#include <linux/module.h>
#include <linux/mutex.h>
#include <linux/string.h>
#include <linux/sysfs.h>

#include "iec_kmod.h"

static struct kobject *iec_root_kobj;
static struct kobject *iec_cfg_kobj;

static const char *const iec_state_names[] = { "stopped", "running", "fault" };

static ssize_t status_show(struct kobject *kobj, struct kobj_attribute *attr,
			   char *buf)
{
	struct iec_resource *r;
	int len = 0;
	u32 i;

	len += sysfs_emit_at(buf, len, "configuration %s source %s interface %s\n",
			     iec_cfg->name, iec_cfg->source_hash,
			     iec_cfg->iface_hash);
	mutex_lock(&iec_resources_lock);
	list_for_each_entry(r, &iec_resources, node) {
		len += sysfs_emit_at(buf, len, "resource %s module %s cpu %d\n",
				     r->name, module_name(r->owner), r->cpu);
		for (i = 0; i < r->ntasks; i++) {
			struct iec_task *t = &r->tasks[i];
			struct iec_task_stats *s = &t->stats;
			int st = READ_ONCE(t->state);

			len += sysfs_emit_at(buf, len,
				"task %s.%s state %s interval_ns %lld priority %d cycles %llu overruns %llu exec_min_ns %lld exec_max_ns %lld exec_avg_ns %lld latency_max_ns %lld faults %llu fault %s pou %s line %d\n",
				r->name, t->name,
				st >= 0 && st <= IEC_TASK_FAULT ? iec_state_names[st] : "?",
				t->interval_ns, t->priority, s->cycles,
				s->overruns, s->exec_min_ns, s->exec_max_ns,
				s->cycles ? div64_s64(s->exec_sum_ns, s->cycles) : 0,
				s->latency_max_ns, s->faults,
				s->fault_code ? iec_fault_name(s->fault_code) : "none",
				s->fault_pou ? s->fault_pou : "-", s->fault_line);
		}
	}
	mutex_unlock(&iec_resources_lock);
	for (i = 0; i < iec_cfg->nslots; i++) {
		struct iec_gft_slot *slot = &iec_cfg->slots[i];
		struct iec_program_type *p;

		rcu_read_lock();
		p = rcu_dereference_raw(slot->cur);
		len += sysfs_emit_at(buf, len, "slot %u %s interface %016llx module %s build %s since %lld publications %llu\n",
				     i, slot->type_name, slot->iface_hash,
				     p ? module_name(p->owner) : "-",
				     p ? p->build_id : "-",
				     ktime_to_ns(slot->since), slot->publications);
		rcu_read_unlock();
	}
	return len;
}

static int iec_control_resource(const char *name, bool start)
{
	struct iec_resource *r;
	int ret = -ENOENT;

	mutex_lock(&iec_resources_lock);
	list_for_each_entry(r, &iec_resources, node) {
		if (strcmp(name, "all") && strcmp(name, r->name))
			continue;
		if (start)
			ret = r->start(r);
		else {
			r->stop(r);
			ret = 0;
		}
		if (ret)
			break;
	}
	mutex_unlock(&iec_resources_lock);
	return ret;
}

static ssize_t control_store(struct kobject *kobj, struct kobj_attribute *attr,
			     const char *buf, size_t count)
{
	char cmd[16], arg[64];
	int ret;
	u32 slot;

	if (sscanf(buf, "%15s %63s", cmd, arg) != 2)
		return -EINVAL;
	if (!strcmp(cmd, "start") || !strcmp(cmd, "stop")) {
		ret = iec_control_resource(arg, cmd[2] == 'a');
	} else if (!strcmp(cmd, "clear")) {
		if (!strcmp(arg, "all")) {
			ret = 0;
			for (slot = 0; slot < iec_cfg->nslots && !ret; slot++)
				ret = iec_gft_clear(slot);
		} else {
			ret = kstrtou32(arg, 10, &slot);
			if (!ret)
				ret = iec_gft_clear(slot);
		}
	} else {
		ret = -EINVAL;
	}
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
	return 0;

err_cfg:
	kobject_put(iec_cfg_kobj);
err_root:
	kobject_put(iec_root_kobj);
	return ret;
}

void iec_ctl_exit(void)
{
	sysfs_remove_group(iec_cfg_kobj, &iec_group);
	kobject_put(iec_cfg_kobj);
	kobject_put(iec_root_kobj);
}
