// SPDX-License-Identifier: GPL-2.0-only OR MIT
/*
 * iec_ctl_sysfs.c - the sysfs side of the configuration's control plane,
 * for people and shell scripts (status 0444, control 0200; the privilege
 * checks of iec_ctl.c on every read and write, not only the file mode):
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
 *   The control file takes exactly one command: one line of known words
 *   separated by single spaces, at most one trailing newline, nothing
 *   after it (no NUL, no second line).  A control write runs under
 *   iec_ctl_mutex, as a netlink command does.
 */
#include <linux/capability.h>
#include <linux/kobject.h>
#include <linux/module.h>
#include <linux/mutex.h>
#include <linux/rcupdate.h>
#include <linux/string.h>
#include <linux/sysfs.h>

#include "iec_kmod.h"
#include "iec_ctl.h"

static struct kobject *iec_root_kobj;
static struct kobject *iec_cfg_kobj;

static const char *const iec_state_names[] = { "stopped", "running", "fault" };

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

	/* the file mode is not enough: a root without capabilities is refused */
	if (!capable(CAP_NET_ADMIN) && !iec_monitor())
		return -EPERM;
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

		/* the module of a replaced program type is freed only after
		 * the synchronize_rcu() of module removal
		 */
		rcu_read_lock();
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

/*
 * Splits the one line of a control write into at most @max words (single
 * spaces between them); -EINVAL for anything else: a NUL, a second line,
 * a control character, an empty word, too many words.
 */
static int iec_control_words(char *line, size_t count, char **words, int max)
{
	int n = 0;
	char *p;

	if (count && line[count - 1] == '\n')
		count--;
	line[count] = '\0';
	/* printable ASCII only (names are IEC identifiers) */
	for (p = line; p < line + count; p++)
		if ((u8)*p < 0x20 || (u8)*p > 0x7e)
			return -EINVAL;
	while ((p = strsep(&line, " "))) {
		if (!*p || n == max)
			return -EINVAL;
		words[n++] = p;
	}
	return n;
}

static ssize_t control_store(struct kobject *kobj, struct kobj_attribute *attr,
			     const char *buf, size_t count)
{
	char line[96], *w[3];
	int ret, n;
	u32 slot, run_ms = 0;

	/* the file mode is not enough: a root without capabilities is refused */
	if (!capable(CAP_NET_ADMIN))
		return -EPERM;
	if (count >= sizeof(line))
		return -EINVAL;
	memcpy(line, buf, count);
	n = iec_control_words(line, count, w, ARRAY_SIZE(w));
	if (n < 2)
		return -EINVAL;
	if (!strcmp(w[0], "run")) {
		if (n != 3 || kstrtou32(w[2], 10, &run_ms) || !run_ms)
			return -EINVAL;
	} else if (n != 2) {
		return -EINVAL;
	}
	mutex_lock(&iec_ctl_mutex);
	if (!strcmp(w[0], "start") || !strcmp(w[0], "stop")) {
		ret = iec_control_resource(w[1], w[0][2] == 'a', 0);
	} else if (!strcmp(w[0], "run")) {
		ret = iec_control_resource(w[1], true, run_ms);
	} else if (!strcmp(w[0], "clear")) {
		if (!strcmp(w[1], "all")) {
			ret = iec_gft_clear(-1);
		} else {
			ret = kstrtou32(w[1], 10, &slot);
			if (!ret)
				ret = iec_gft_clear(slot);
		}
	} else {
		ret = -EINVAL;
	}
	mutex_unlock(&iec_ctl_mutex);
	return ret ? ret : count;
}

static struct kobj_attribute status_attr = __ATTR(status, 0444, status_show, NULL);
static struct kobj_attribute control_attr = __ATTR(control, 0200, NULL, control_store);

static struct attribute *iec_attrs[] = {
	&status_attr.attr,
	&control_attr.attr,
	NULL,
};

static const struct attribute_group iec_group = {
	.attrs = iec_attrs,
};

int iec_ctl_sysfs_init(void)
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

void iec_ctl_sysfs_exit(void)
{
	sysfs_remove_group(iec_cfg_kobj, &iec_group);
	kobject_put(iec_cfg_kobj);
	kobject_put(iec_root_kobj);
}
